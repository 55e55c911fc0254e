"""Shared utilities with no model, data or motion knowledge:
:mod:`.files` (the one atomic write and the input / output path checks)
and :mod:`.cache` (the one cache root)."""
