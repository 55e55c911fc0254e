"""``python -m satagraph``: the command line."""
from satagraph.cli import run

run()
