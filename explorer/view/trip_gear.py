"""The drawing of the trip gear (explorer.gears.trip_gear): the stock valve (opening downwards); a
latch cam drives a rod whose latch pushes a catch collar on the spindle from above and slides off it
at the trip; a dashpot sits above the spindle (see `_trip_geometry`)."""

from __future__ import annotations

import math
from dataclasses import replace
from types import MappingProxyType

import numpy as np
import trimesh

from ..lift.contours.translating import translating_profile
from . import translating_roller as stock
from .drawing import quat_about_y
from .gear_parts import (TWO_PI, LeverGearView, bar_between, concat, disc, extrude_contour, ident, pin, roller, sizes,
                         world)

COLORS = MappingProxyType({
    "latch": (230, 200, 60),
    "catch": (200, 70, 70),
    "dashpot": (110, 112, 120),
    "dashpot_piston": (170, 120, 90),
    "rod": (150, 160, 175),
})


def _trip_part_setting(scene, key):
    """[gear.trip] `key` when the scene's gear section has it (latch_width, latch_depth)."""
    try:
        return scene.gear.part("trip").get(key)
    except (AttributeError, KeyError, TypeError):
        return None


def _dashpot_bore(scene, default: float) -> float:
    """Bore radius of the scene's active dashpot ([gear.air_dashpot] or [gear.oil_dashpot]
    diameter), or `default` for a gear without a buffer."""
    try:
        buffer = scene.gear.part("trip")["buffer"]
        return 0.5 * float(scene.gear.part(f"{buffer}_dashpot")["diameter"]) if buffer != "none" else default
    except (AttributeError, KeyError, TypeError):
        return default


def _trip_geometry(scene, lift, lay) -> dict:
    """Where the trip gear's parts sit (world x-z, metres), shared by its parts and poses.

    The valve spindle (the stock valve, opening downwards) carries a catch collar under the
    dashpot. The latch is a plate that reaches the catch from the right: it rests `overtravel`
    above the collar, then pushes it down with the latch lift X - s_o; at the trip it slides out
    to the right by its engagement and passes the collar. It slides in a guide at the foot of
    the latch rod, which runs up beside the dashpot to a roller under the latch cam: a cam for
    the scene's latch law (valve-referred: the drawing has the ratio 1), turned upside down so
    that its lift pushes the roller, rod and latch down. The cam sits above the dashpot, the rod
    and roller clear of its side."""
    w, half = sizes(lay)
    rv, rs = lay.valve_radius, lay.stem_radius
    latch = lift.latch
    stroke = float(latch.height)
    depth = _trip_part_setting(scene, "latch_depth") or 0.3 * rv
    face = _trip_part_setting(scene, "latch_width") or 0.5 * w
    catch_r = rs + depth  # the collar: the latch bears on its rim, `depth` wide
    plate = max(0.12 * rv, half)  # thickness of latch plate and collar
    gap = 0.15 * rv
    # collar underside at rest: high enough on the spindle that the tripped latch, at the bottom
    # of its stroke beside the closed valve, stays `gap` above the spring retainer
    catch_z = max(lay.stem_top_rest + 2.0 * half,
                  lay.stem_top_rest - lay.retainer_drop + gap + stroke - plate - lift.overtravel)
    latch_rest = catch_z + plate + lift.overtravel  # latch face with X = 0
    bore = _dashpot_bore(scene, 1.1 * rv)  # the scene's dashpot
    outer = 1.25 * bore
    # piston at rest: the bore (top - 1.2 stroke .. top + 1.8 stroke) starts `gap` above the latch
    top = latch_rest + plate + gap + 1.2 * stroke
    dashpot_top = top + 1.8 * stroke
    roller = 0.3 * stroke
    base = 1.0 * stroke  # a cam about as large as the lift: moderate pressure angles for the usual laws
    rod_x = lay.valve_x + outer + gap + roller
    theta = np.linspace(0.0, TWO_PI, 720, endpoint=False)
    theta = np.unique(np.concatenate([theta, np.mod(np.asarray(latch.breakpoints(), dtype=float), TWO_PI)]))
    contour = translating_profile(latch, theta, base, roller, 0.0).contour
    reach = float(np.max(np.hypot(contour[:, 0], contour[:, 1])))
    prime = base + roller
    # the cam's swept disc clears the dashpot's top by `gap`
    cam_z = max(dashpot_top + gap + reach, latch_rest + 2.0 * prime)
    return dict(
        w=w, half=half, stroke=stroke, depth=depth, face=face, catch_r=catch_r, plate=plate, bore=bore,
        outer=outer, top=top, catch_z=catch_z, latch_rest=latch_rest, roller=roller, base=base, rod_x=rod_x,
        contour=contour, cam=(rod_x, cam_z), rod_length=cam_z - prime - latch_rest, slide=depth + gap,
    )


def trip_parts(scene, lift, lay):
    g = _trip_geometry(scene, lift, lay)
    w, plate, stroke = g["w"], g["plate"], g["stroke"]
    rs = lay.stem_radius
    reach_x = g["rod_x"] - lay.valve_x
    # latch: local origin on the valve axis at its face (underside); it starts over the stem's
    # surface, so it never meets the spindle, and ends beyond the rod's guide by the slide
    latch = extrude_contour(np.array([[rs, 0.0], [reach_x + g["slide"] + 0.5 * g["roller"], 0.0],
                                      [reach_x + g["slide"] + 0.5 * g["roller"], plate], [rs, plate]]), g["face"])
    collar = trimesh.creation.cylinder(radius=g["catch_r"], height=plate, sections=48)
    collar.apply_translation([0.0, 0.0, 0.5 * plate])
    # latch rod: local origin at the roller's centre; the guide at its foot embraces the latch
    rod_half = 0.3 * g["roller"]
    length = g["rod_length"]
    guide = extrude_contour(np.array([[-2.5 * rod_half, -length - 0.8 * plate], [2.5 * rod_half, -length - 0.8 * plate],
                                      [2.5 * rod_half, -length + 1.8 * plate], [-2.5 * rod_half, -length + 1.8 * plate]]),
                            1.3 * g["face"])
    fork = [pin(0.0, 0.0, 0.3 * g["roller"], 1.6 * lay.roller_width)]
    bar = bar_between((0.0, -length), (0.0, 0.0), rod_half, 0.5 * w)
    bar.apply_translation([0.0, 0.0, -length])  # _bar_between draws in the frame of its first point
    rod = concat([bar, guide, *fork])
    cam = extrude_contour(g["contour"], 0.8 * w)
    shaft = 0.3 * g["base"]
    camshaft = concat([disc(shaft, 3.0 * w), pin(0.0, shaft, 0.3 * shaft, 3.0 * w)])
    # dashpot: the piston (top of the rod, 0.4 stroke thick) runs from z = top down by the lift,
    # at most the latch stroke: the bore spans top - 1.2 stroke .. top + 1.8 stroke
    bore = g["bore"]
    top = g["top"]
    cylinder = trimesh.creation.annulus(r_min=bore, r_max=g["outer"], height=3.0 * stroke, sections=48)
    cylinder.apply_translation([lay.valve_x, 0.0, top + 0.3 * stroke])
    piston = trimesh.creation.cylinder(radius=0.98 * bore, height=0.4 * stroke, sections=48)
    piston_rod = trimesh.creation.cylinder(radius=rs, height=top - lay.stem_top_rest, sections=16)
    piston_rod.apply_translation([0.0, 0.0, 0.5 * (top - lay.stem_top_rest)])
    piston.apply_translation([0.0, 0.0, top - lay.stem_top_rest + 0.2 * stroke])
    return {"latch": latch, "catch": collar, "dashpot": cylinder, "dashpot_piston": concat([piston_rod, piston]),
            "rod": rod, "roller": roller(lay, g["roller"]), "cam": cam, "camshaft": camshaft}


def trip_poses(scene, lift, lay, theta):
    g = _trip_geometry(scene, lift, lay)
    n = theta.size
    latch = np.asarray(lift.latch.derivatives(theta)[0])
    s = np.maximum(np.asarray(lift.derivatives(theta)[0]) - lift.overtravel, 0.0)
    phi = np.mod(theta - lift.start, TWO_PI)
    # tripped: from the release until the latch is back above its catching height
    tripped = (phi >= lift.phi_trip) & (latch > lift.overtravel - 1e-12)
    # the latch face meets the collar after the over-travel, then both move by X - s_o
    latch_z = g["latch_rest"] - latch
    cx, cz = g["cam"]
    # the cam is drawn upside down (turned by pi): its lift points down, onto the roller
    spin = _triproller_spin(scene, lift, g, theta)
    return {
        "latch": (np.column_stack([lay.valve_x + np.where(tripped, g["slide"], 0.0), np.zeros(n), latch_z]), ident(n)),
        "catch": (np.column_stack([np.full(n, lay.valve_x), np.zeros(n), g["catch_z"] - s]), ident(n)),
        "dashpot": (world(n, 0.0, 0.0), ident(n)),
        "dashpot_piston": (np.column_stack([np.full(n, lay.valve_x), np.zeros(n), lay.stem_top_rest - s]), ident(n)),
        "rod": (np.column_stack([np.full(n, g["rod_x"]), np.zeros(n), latch_z + g["rod_length"]]), ident(n)),
        "roller": (np.column_stack([np.full(n, g["rod_x"]), np.zeros(n), latch_z + g["rod_length"]]), quat_about_y(-spin)),
        "cam": (world(n, cx, cz), quat_about_y(-(theta + math.pi))),
        "camshaft": (world(n, cx, cz), quat_about_y(-(theta + math.pi))),
    }


def _triproller_spin(scene, lift, g, theta):
    """The latch roller rolling on its cam: the translating roller's roller_spin for a roller
    of the drawing's base circle and radius (turning the whole cam and follower by pi changes
    neither the spin's sense nor its rate)."""
    follower = replace(scene.follower, base_radius=g["base"], roller_radius=g["roller"], offset=0.0)
    return stock.roller_spin(scene.with_changes(follower=follower), lift.latch, np.asarray(theta, dtype=float))


class TripGearView(LeverGearView):
    colors = COLORS

    def gear_parts(self, scene, lift, lay) -> dict:
        return trip_parts(scene, lift, lay)

    def gear_poses(self, scene, lift, lay, theta) -> dict:
        return trip_poses(scene, lift, lay, theta)


VIEW = TripGearView()
