"""How far a grasp on the physics cell may read from the held object's known width."""

# MuJoCo's contacts are soft: under the grip force each pad sinks a little into the held object, so
# the gap between the pads falls short of the object's width (about 0.6 mm at rFR 150, with MuJoCo
# 3.2.3 and 4.0 alike). Metres.
GAP_TOLERANCE = 0.001


def gpo_tolerance(scale):
    """GAP_TOLERANCE in counts of the position register (gripper_model.RegisterScale `scale`), plus the
    half count gPO's rounding adds."""
    return GAP_TOLERANCE * scale.counts_per_metre + 0.5
