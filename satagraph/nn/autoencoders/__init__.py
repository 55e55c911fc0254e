"""Motion autoencoders, all keeping the :class:`MotionAutoencoder` contract
(encode, decode onto any target, latent rate): :class:`SATA` (its :class:`SATAEncoder` and
:class:`SATADecoder`, one latent per frame and joint, built on one :class:`SATAStack`) and two
baselines, :class:`SAME` (skeleton-agnostic, one latent per frame) and
:class:`PaddedRVQ` (frames zero-padded to a fixed joint count)."""
from satagraph.nn.autoencoders.base import MotionAutoencoder
from satagraph.nn.autoencoders.decoder import SATADecoder
from satagraph.nn.autoencoders.encoder import SATAEncoder, node_motion_features
from satagraph.nn.autoencoders.padded import PaddedRVQ
from satagraph.nn.autoencoders.same import SAME
from satagraph.nn.autoencoders.sata import SATA
from satagraph.nn.autoencoders.stack import SATAStack

__all__ = ["MotionAutoencoder", "SATA", "SATAStack", "SATAEncoder", "SATADecoder",
           "node_motion_features", "SAME", "PaddedRVQ"]
