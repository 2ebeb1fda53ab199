#!/bin/sh
# Regenerate the host package's copies of the protocol artefacts from protocol/.
# Run after every change of protocol/landscape.proto, .dbc or .options;
# tests/host/test_generated.py fails while the committed copies are stale.
set -eu
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/.." && pwd)
out="$here/src/landscape/_generated"
protoc -I"$root/protocol" -I/usr/include --python_out="$out" --pyi_out="$out" \
  --descriptor_set_out="$out/landscape.desc" "$root/protocol/landscape.proto"
cp "$root/protocol/landscape.dbc" "$out/landscape.dbc"
cp "$root/protocol/landscape.options" "$out/landscape.options"
echo "updated $out/landscape_pb2.py(i), landscape.desc, landscape.dbc and landscape.options"
