"""Scene keys of today's valve trains (issue #24): [gear.*] sub-tables read into SI dicts, and the
gears built from them; the gear plug-ins (gears/bucket_tappet.py, finger_follower.py,
rocker_arm.py) call them, keyed by part name ("bucket", "finger", "rocker"), so no follower type is
named here. The keys,
units, ranges and defaults are listed in docs/theory/modern-gears.md. Points are [x, y] pairs
from the camshaft's centre (x to the right, y up, the cam turning counter-clockwise), angles
counter-clockwise from +x, lengths with units as everywhere.

bucket           follower.base_radius; [gear.tappet] face_diameter, face_radius (absent: a flat
                 face), offset (along the camshaft), cam_width, face_margin
finger           follower.base_radius, follower.roller_radius (cam_side = "roller");
                 [gear.finger] pivot (the lash adjuster's ball), arm, side, cam_side, pad_radius
                 (cam_side = "pad"; absent: flat), face_angle, width, stiffness (the arm's and the lash
                 adjuster's, at the roller or pad along its travel); [gear.valve_pad] arm, angle,
                 radius; [gear.valve] axis, axis_point, tip_radius; [gear.lash_adjuster] (drawing)
rocker           with [gear.lifter] the OHV pushrod train: [gear.lifter] type, face_radius,
                 roller_radius, offset, socket_height, width, stiffness (lifter and pushrod, along the
                 lifter's axis); [gear.rocker] pivot, cup (the
                 pushrod's upper ball with the valve closed); without it the OHC rocker:
                 [gear.rocker] as [gear.finger]. [gear.valve_pad] angle is measured from the
                 rocker's reference direction (pivot -> roller, pad crown or cup).
"""

from __future__ import annotations

import math
from typing import Any, Mapping

from ..core.errors import InputError
from ..core.ranges import check_range
from ..core.reader import Table
from ..core.units import to_si

# what parse_parts and build_modern_gear take (part names, not follower types: this module is shared
# by the gears, and the plug-in check keeps a follower type out of shared modules): the bucket, or the arm (an end-pivot finger, a
# centre-pivot rocker with or without [gear.lifter]); the follower types are their gears' to name
MODERN_TYPES = ("bucket", "finger", "rocker")
SIDES = {"left": 1, "right": -1}
CAM_SIDES = ("roller", "pad")
LIFTER_TYPES = ("flat", "roller")


def _point(t: Table, name: str, required: bool = True):
    if not t.has(name):
        if required:
            raise t.error(name, 'missing key: a point [x, y], such as ["-32 mm", "-36 mm"]')
        return None
    raw = t.raw(name)
    if not isinstance(raw, list) or len(raw) != 2:
        raise t.error(name, 'expected a point [x, y], such as ["-32 mm", "-36 mm"]')
    out = []
    for i, v in enumerate(raw):
        key = f"{t.key(name)}[{i}]"
        out.append(check_range(to_si(v, "length", file=t.file, key=key), "length", file=t.file, key=key, shown=v))
    return tuple(out)


def _optional(t: Table, name: str, dimension: str = "length", **kw):
    return t.quantity(name, dimension, **kw) if t.has(name) else None


def _tappet(t: Table) -> dict:
    t.reject_unknown(("face_diameter", "face_radius", "offset", "cam_width", "face_margin"))
    return {
        "face_diameter": _optional(t, "face_diameter", positive=True),
        "face_radius": _optional(t, "face_radius", positive=True),
        "offset": t.quantity("offset", "length", 0.0),
        "cam_width": _optional(t, "cam_width", positive=True),
        "face_margin": t.quantity("face_margin", "length", 0.0, nonnegative=True),
    }


def _arm(t: Table) -> dict:
    t.reject_unknown(("pivot", "arm", "side", "cam_side", "pad_radius", "face_angle", "width", "stiffness"))
    cam_side = t.string("cam_side", "roller", choices=CAM_SIDES)
    if cam_side == "roller":
        for name in ("pad_radius", "face_angle"):
            if t.has(name):
                raise t.error(name, 'applies to cam_side = "pad" only (a roller\'s radius is follower.roller_radius)')
    return {
        "pivot": _point(t, "pivot"),
        "arm": t.quantity("arm", "length", positive=True),
        "side": t.string("side", "left", choices=tuple(SIDES)),
        "cam_side": cam_side,
        "pad_radius": _optional(t, "pad_radius", positive=True),
        "face_angle": t.quantity("face_angle", "angle", -0.5 * math.pi),
        "width": _optional(t, "width", positive=True),
        "stiffness": _optional(t, "stiffness", "stiffness", positive=True),
    }


def _valve_pad(t: Table) -> dict:
    t.reject_unknown(("arm", "angle", "radius"))
    return {
        "arm": t.quantity("arm", "length", positive=True),
        "angle": t.quantity("angle", "angle", 0.0),
        "radius": t.quantity("radius", "length", positive=True),
    }


def _valve(t: Table) -> dict:
    t.reject_unknown(("axis", "axis_point", "tip_radius"))
    return {
        "axis": _optional(t, "axis", "angle"),
        "axis_point": _point(t, "axis_point", required=False),
        "tip_radius": _optional(t, "tip_radius", positive=True),
    }


def _lash_adjuster(t: Table) -> dict:
    t.reject_unknown(("body_diameter", "body_length"))
    return {"body_diameter": _optional(t, "body_diameter", positive=True),
            "body_length": _optional(t, "body_length", positive=True)}


def _lifter(t: Table) -> dict:
    kind = t.string("type", "flat", choices=LIFTER_TYPES)
    if kind == "flat":
        t.reject_unknown(("type", "face_radius", "socket_height", "width", "stiffness"))
    else:
        t.reject_unknown(("type", "roller_radius", "offset", "socket_height", "width", "stiffness"))
    return {
        "type": kind,
        "face_radius": _optional(t, "face_radius", positive=True),
        "roller_radius": t.quantity("roller_radius", "length", positive=True) if kind == "roller" else None,
        "offset": t.quantity("offset", "length", 0.0),
        "socket_height": t.quantity("socket_height", "length", nonnegative=True),
        "width": _optional(t, "width", positive=True),
        "stiffness": _optional(t, "stiffness", "stiffness", positive=True),
    }


def _pushrod_rocker(t: Table) -> dict:
    t.reject_unknown(("pivot", "cup"))
    return {"pivot": _point(t, "pivot"), "cup": _point(t, "cup")}


def parse_parts(table: Table, kind: str) -> dict[str, Mapping[str, Any]]:
    """[gear] of a modern gear -> {sub-table: SI dict}; one-line InputErrors naming the key."""
    if kind not in MODERN_TYPES:
        raise InputError(table.file, "follower.type", f"not one of today's valve trains: {kind!r}")
    if kind == "bucket":
        parsers, optional = {"tappet": _tappet}, set()
    elif kind == "finger":
        parsers = {"finger": _arm, "valve_pad": _valve_pad, "valve": _valve, "lash_adjuster": _lash_adjuster}
        optional = {"valve", "lash_adjuster"}
    else:
        pushrod = table.table("lifter", required=False) is not None
        parsers = {"lifter": _lifter, "rocker": _pushrod_rocker if pushrod else _arm, "valve_pad": _valve_pad,
                   "valve": _valve}
        optional = {"valve"} | (set() if pushrod else {"lifter"})
    table.reject_unknown(tuple(parsers))
    out = {}
    for name, parser in parsers.items():
        sub = table.table(name, required=False)
        if sub is None:
            if name in optional:
                continue
            raise InputError(table.file, f"gear.{name}", f"missing section: follower.type '{kind}' needs [gear.{name}]")
        out[name] = parser(sub)
    return out


def build_modern_gear(kind: str, parts: Mapping[str, Mapping[str, Any]], *, base_radius: float, roller_radius: float,
                      lift, file: str = "<memory>", contour=None, n: int = 3600):
    """The gear for parsed parts and the valve-referred lift law (or a given contour), checked
    over a revolution (its geometry errors name the scene keys)."""
    # local: this module is the gears' keys (no numpy); a gear's geometry loads when it is built
    from .arm import CamSide, make_arm_gear
    from .flat_face import Tappet, analyse_bucket, synthesise_bucket
    from .pushrod import Lifter, make_pushrod_train

    law = None if contour is not None else lift
    if kind == "bucket":
        p = parts["tappet"]
        tappet = Tappet(base_radius=base_radius, face_radius=p["face_radius"] or math.inf,
                        face_diameter=p["face_diameter"], offset=p["offset"], cam_width=p["cam_width"],
                        face_margin=p["face_margin"], file=file)
        return analyse_bucket(tappet, contour, n) if contour is not None else synthesise_bucket(tappet, lift, n)
    valve_pad, valve = parts["valve_pad"], parts.get("valve", {})
    common = dict(valve_pad_radius=valve_pad["radius"], valve_axis=valve.get("axis"),
                  valve_axis_point=valve.get("axis_point"), tip_radius=valve.get("tip_radius"), law=law,
                  contour=contour, file=file, n=n)
    if kind == "rocker" and "lifter" in parts:
        f, r = parts["lifter"], parts["rocker"]
        if f["type"] == "roller":
            lifter = Lifter("roller", radius=f["roller_radius"], offset=f["offset"], socket_height=f["socket_height"],
                            width=f["width"])
        else:
            lifter = Lifter("flat", radius=f["face_radius"] or math.inf, socket_height=f["socket_height"], width=f["width"])
        rest = math.atan2(r["cup"][1] - r["pivot"][1], r["cup"][0] - r["pivot"][0])
        centre = (r["pivot"][0] + valve_pad["arm"] * math.cos(rest + valve_pad["angle"]),
                  r["pivot"][1] + valve_pad["arm"] * math.sin(rest + valve_pad["angle"]))
        common.pop("n")
        return make_pushrod_train(base_radius=base_radius, lifter=lifter, rocker_pivot=r["pivot"], cup=r["cup"],
                                  valve_pad_centre=centre, n=n, **common)
    name = kind
    a = parts[name]
    if a["cam_side"] == "roller":
        if not roller_radius > 0.0:
            raise InputError(file, "follower.roller_radius", f"the {kind}'s roller needs roller_radius > 0")
        side = CamSide("roller", a["arm"], roller_radius, width=a["width"])
    else:
        side = CamSide("pad", a["arm"], a["pad_radius"] or math.inf, face_angle=a["face_angle"], width=a["width"])
    radius_key = "follower.roller_radius" if a["cam_side"] == "roller" else f"gear.{name}.pad_radius"
    return make_arm_gear(base_radius=base_radius, pivot=a["pivot"], cam_side=side, branch=SIDES[a["side"]],
                         valve_arm=valve_pad["arm"], valve_angle=valve_pad["angle"], kind=kind,
                         arm_key=f"gear.{name}", pad_key="gear.valve_pad", radius_key=radius_key, **common)
