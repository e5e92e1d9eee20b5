"""The seeds' other valve gears: pivoted roller lever, eccentric-driven rocking cam, eccentric
rolling lever (Waelzhebel), trip gear with air or oil dashpot.

Each gear turns its geometry into what the rest of the pipeline consumes: a valve-referred lift
curve (derivatives(theta) -> [L, L', L'', L'''], breakpoints()) with analytic derivatives, so the
kinematics, lash, forces and elastic effects work on it unchanged; the 'gear' effect adds what
is particular to each gear (lever angles and ratios, pressure angle, buffer forces ...).

This package file stays light: scene.py imports GEAR_TYPES while validating follower.type. The
gears themselves are listed in explorer.gears.registry (what the generic code asks of each).
"""

from .registry import GEARS

GEAR_TYPES = tuple(GEARS)  # ("pivoted-roller", "rocking-cam", "rolling-lever", "trip")

# Colours (RGB 0-255) of the 3D parts these gears add to explorer.view.parts.
GEAR_PART_COLORS: dict[str, tuple[int, int, int]] = {
    "roller_lever": (90, 170, 110),
    "rod": (150, 160, 175),
    "valve_lever": (70, 150, 95),
    "valve_lever_pivot": (95, 100, 110),
    "eccentric": (214, 126, 44),
    "eccentric_rod": (150, 160, 175),
    "rocking_cam": (214, 126, 44),
    "cam_pivot": (95, 100, 110),
    "rolling_lever": (214, 126, 44),
    "latch": (230, 200, 60),
    "catch": (200, 70, 70),
    "dashpot": (110, 112, 120),
    "dashpot_piston": (170, 120, 90),
}
