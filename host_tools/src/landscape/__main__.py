"""python -m landscape: the CLI."""
from .cli import main

main()
