"""``satagraph cache``: what the processed-feature cache holds, and its
upkeep. Every file a run reads is cached once per preprocessing config
(``satagraph.data.cache``); nothing removes entries by itself, so a cache
grows with every dataset, config and feature version a machine has seen.

Examples::

    satagraph cache                   # where it is, how many entries, how big
    satagraph cache --prune 30        # remove entries no run has read for 30 days
    satagraph cache --clear           # remove every entry (rebuilt when needed)
"""
from __future__ import annotations

import argparse
import math
import time
from pathlib import Path
from typing import Optional

from satagraph.cli.arguments import positive_float


def _size(n: int) -> str:
    """Bytes in words: ``3.2 GB``."""
    if n < 1000:
        return f"{n} B"
    power = min(3, int(math.log10(n) // 3))
    return f"{n / 1000 ** power:.1f} {('KB', 'MB', 'GB')[power - 1]}"


def _count(n: int, kind: str = "") -> str:
    return f"{n} {kind}entr{'y' if n == 1 else 'ies'}"


def _ago(stamp: Optional[float], now: float) -> str:
    """How long ago :obj:`stamp` was, in days (hours under one)."""
    seconds = max(0.0, now - stamp)
    if seconds < 3600:
        return f"{seconds / 60:.0f} min ago"
    return f"{seconds / 3600:.0f} h ago" if seconds < 86400 else f"{seconds / 86400:.0f} days ago"


def add_cache_parser(subparsers: "argparse._SubParsersAction") -> argparse.ArgumentParser:
    """Register ``satagraph cache [--dir DIR] [--prune DAYS | --clear]``."""
    parser = subparsers.add_parser(
        "cache", help="show or prune the processed-feature cache",
        description="Show the processed-feature cache (every BVH file a run reads is\n"
        "cached once per preprocessing config, so that the next run starts fast),\n"
        "or remove entries from it: a removed entry is computed again when a run\n"
        "needs it. Only the cache's own entries are touched.",
        formatter_class=argparse.RawDescriptionHelpFormatter,
        epilog="examples:\n  satagraph cache\n  satagraph cache --prune 30\n"
               "  satagraph cache --clear --dir /scratch/cache")
    parser.add_argument("--dir", metavar="DIR", default=None,
                        help="the cache root, as a config's data.cache_dir gives it "
                             "(default: $SATAGRAPH_CACHE or ~/.cache/satagraph)")
    what = parser.add_mutually_exclusive_group()
    what.add_argument("--prune", metavar="DAYS", type=positive_float, default=None,
                      help="remove the entries no run has read for DAYS days")
    what.add_argument("--clear", action="store_true", help="remove every entry")
    return parser


def run_cache(args: argparse.Namespace) -> int:
    """Print the cache's usage, after pruning or clearing it when asked."""
    from satagraph.data.cache import cache_usage, feature_cache_dir, prune_cache
    folder = feature_cache_dir(args.dir)
    if args.dir and not folder.is_dir() and cache_usage(Path(args.dir)).entries:
        raise ValueError(f"cache --dir {args.dir}: the feature folder itself; --dir takes the "
                         f"cache root that holds it: --dir {Path(args.dir).parent}")
    if args.prune is not None or args.clear:
        removed, freed = prune_cache(folder, None if args.clear else args.prune)
        print(f"removed {_count(removed)} ({_size(freed)}) from {folder}")
    usage, now = cache_usage(folder), time.time()
    if not usage.entries:
        print(f"{folder}: no feature entries")
        return 0
    print(f"{folder}: {_count(usage.entries, 'feature ')}, {_size(usage.bytes)}; last read "
          f"{_ago(usage.newest, now)}, least recently {_ago(usage.oldest, now)} "
          "(satagraph cache --prune DAYS removes the entries unread for DAYS days)")
    return 0
