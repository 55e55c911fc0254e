"""File input and output."""
from satagraph.io.bvh_reader import read_bvh
from satagraph.io.bvh_writer import channel_values, write_bvh
from satagraph.io.errors import BVHError

__all__ = ["read_bvh", "write_bvh", "channel_values", "BVHError"]
