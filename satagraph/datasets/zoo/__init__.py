r"""A procedural zoo: skeletons of several body plans and physically sensible
motions for them, written as BVH files with a manifest (no data needed).

Body plans (:data:`SPECIES`): ``biped`` (humans), ``quadruped`` (with and
without tail), ``bird`` (two legs, two wings), ``hexapod`` (insects),
``snake`` (one long chain), ``fowl`` (birds in the ``Bip01`` and
finger-named-wing dialects), ``crab`` (three walking-leg pairs, claws, eye
stalks), ``spider`` (four leg pairs) and ``longtail`` (a quadruped of about
100 joints with a 32+ joint tail). Each has several skeleton variants
(:data:`VARIANTS`) that differ in proportions, joint counts, rotation orders
and naming conventions (``LeftUpLeg`` / ``thigh.L`` / ``l_hip``), all chosen
so that :func:`satagraph.semantics.describe_joints` reads them well.

Legged motions are built from a gait: per-leg phases and a duty factor give
stance and swing intervals; a stance foot stays planted where it landed
(height 0, zero velocity), a swing foot travels on an arc to the next
landing spot beside the moving body; two-bone IK with a knee pole poses the
legs, and the body height is lowered wherever a planted foot would be out
of reach. Clip kinds (:data:`CLIP_KINDS`): ``walk``, ``turn``, ``speed``
(speed change), ``idle``, ``trot`` (quadrupeds), ``start`` and ``stop``
(from and to a standstill), ``look`` (head, neck, tail and arms turning
slowly), ``jump`` (crouch, flight, landing) and ``reach`` (bipeds: one arm
raised and lowered); gestures (:data:`GESTURE_KINDS`, drawn by the endless
zoo only when asked for): ``bow`` and ``wave`` (bipeds), ``sit`` and ``lie``
(quadrupeds: down in place, then up again). Snakes slither:
every joint follows the path of the head.

Exporter dialects (:mod:`satagraph.datasets.zoo.dialects`) re-express a clip
exactly with another up axis (:data:`UP_AXES`), unit, rest pose and noisy
joint names; :func:`write_zoo` writes them and records the truth in the
manifest (``up_axis``, ``scale``, ``height_m``, ...).

Example::

    from satagraph.datasets.zoo import Dialect, write_zoo
    rows = write_zoo("zoo", species=["quadruped", "snake"], clips=3, seed=1)
    rows = write_zoo("zoo_zup", species=["crab"], dialects=[Dialect("+Z", "cm")])
"""
from satagraph.datasets.zoo.dialects import (NOISE_STYLES, REST_POSES, UNITS, UP_AXES,
                                             Dialect, DialectVariant, add_name_noise,
                                             apply_dialect, change_rest_pose,
                                             dialect_variants, export_dialect,
                                             rest_pose_rotations, unit_scale, up_rotation)
from satagraph.datasets.zoo.motions import (GAITS, ClipFacts, generate_clip,
                                            generate_clip_with_facts)
from satagraph.datasets.zoo.rigs import STYLES, Leg, Sway, ZooRig
from satagraph.datasets.zoo.species import (ALL_KINDS, CLIP_KINDS, GESTURE_KINDS, SPECIES,
                                            VARIANTS, zoo_rigs)
from satagraph.datasets.zoo.writer import (DIALECT_COLUMNS, LICENCE, MANIFEST_COLUMNS,
                                           MOTION_COLUMNS, write_dialect_zoo, write_zoo)

__all__ = ["ALL_KINDS", "CLIP_KINDS", "GESTURE_KINDS", "ClipFacts", "DIALECT_COLUMNS", "GAITS",
           "LICENCE", "MANIFEST_COLUMNS", "MOTION_COLUMNS", "generate_clip_with_facts",
           "NOISE_STYLES", "REST_POSES", "SPECIES", "STYLES", "UNITS", "UP_AXES",
           "VARIANTS", "Dialect", "DialectVariant", "Leg", "Sway", "ZooRig",
           "add_name_noise", "apply_dialect", "change_rest_pose", "dialect_variants",
           "export_dialect", "generate_clip", "rest_pose_rotations", "unit_scale",
           "up_rotation", "write_dialect_zoo", "write_zoo", "zoo_rigs"]
