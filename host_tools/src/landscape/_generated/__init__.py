"""Artefacts generated from protocol/ (see host_tools/update_generated.sh). Do not edit."""
