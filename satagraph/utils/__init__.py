"""Shared utilities with no model, data or motion knowledge:
:mod:`.files` (the one atomic write and the input / output path checks),
:mod:`.cache` (the one cache root) and :mod:`.registry` (the one rule of
the name registries)."""
