"""``python -m satagraph``: the command line."""
from satagraph.cli import main

raise SystemExit(main())
