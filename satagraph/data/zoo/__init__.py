r"""A procedural zoo: skeletons of several body plans and physically sensible
motions for them, written as BVH files with a manifest (no data needed).

Body plans (:data:`SPECIES`): ``biped`` (humans), ``quadruped`` (with and
without tail), ``bird`` (two legs, two wings), ``hexapod`` (insects) and
``snake`` (one long chain). Each has several skeleton variants
(:data:`VARIANTS`) that differ in proportions, joint counts, rotation orders
and naming conventions (``LeftUpLeg`` / ``thigh.L`` / ``l_hip``), all chosen
so that :func:`satagraph.data.semantics.describe_joints` reads them well.

Legged motions are built from a gait: per-leg phases and a duty factor give
stance and swing intervals; a stance foot stays planted where it landed
(height 0, zero velocity), a swing foot travels on an arc to the next
landing spot beside the moving body; two-bone IK with a knee pole poses the
legs, and the body height is lowered wherever a planted foot would be out
of reach. Clip kinds (:data:`CLIP_KINDS`): ``walk``, ``turn``, ``speed``
(speed change), ``idle`` and ``trot`` (quadrupeds). Snakes slither: every
joint follows the path of the head.

Example::

    from satagraph.data.zoo import write_zoo
    rows = write_zoo("zoo", species=["quadruped", "snake"], clips=3, seed=1)
"""

from satagraph.data.zoo.motions import GAITS, generate_clip
from satagraph.data.zoo.rigs import STYLES, Leg, Sway, ZooRig
from satagraph.data.zoo.species import CLIP_KINDS, SPECIES, VARIANTS, zoo_rigs
from satagraph.data.zoo.writer import LICENCE, MANIFEST_COLUMNS, write_zoo

__all__ = ["CLIP_KINDS", "GAITS", "LICENCE", "MANIFEST_COLUMNS", "SPECIES",
           "STYLES", "VARIANTS", "Leg", "Sway", "ZooRig", "generate_clip",
           "write_zoo", "zoo_rigs"]
