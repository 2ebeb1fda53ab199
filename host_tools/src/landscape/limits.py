"""The firmware's static field limits, read from the schema's nanopb options.

The firmware allocates every string and repeated field statically from
protocol/landscape.options; a message that does not fit is refused as a whole.
The package ships a copy of that file (``_generated/landscape.options``) so the
host can check inputs against the same numbers instead of a hand-kept copy.
"""
from __future__ import annotations

from functools import lru_cache
from importlib import resources


@lru_cache(maxsize=1)
def nanopb_options() -> dict[str, dict[str, str]]:
    """Every `ls.Message.field key:value ...` line of the options file, by its name."""
    text = resources.files("landscape._generated").joinpath("landscape.options").read_text()
    out: dict[str, dict[str, str]] = {}
    for raw in text.splitlines():
        line = raw.split("#", 1)[0].strip()
        if not line:
            continue
        name, *opts = line.split()
        out[name] = dict(o.split(":", 1) for o in opts if ":" in o)
    return out


def field_option(message: str, field: str, key: str) -> int | None:
    """The integer option `key` (max_count, max_size) of ls.`message`.`field`, or None
    when the options file does not bound it (a `Message.*` line applies to every field)."""
    opts = nanopb_options()
    for name in (f"ls.{message}.{field}", f"ls.{message}.*"):
        value = opts.get(name, {}).get(key)
        if value is not None:
            return int(value)
    return None


def max_count(message: str, field: str) -> int | None:
    """How many items the firmware holds in repeated field `message`.`field`."""
    return field_option(message, field, "max_count")


def max_string_bytes(message: str, field: str) -> int | None:
    """The longest UTF-8 string (in bytes) the firmware holds in `message`.`field`:
    nanopb's max_size counts the terminating zero, so one less."""
    size = field_option(message, field, "max_size")
    return None if size is None else size - 1
