"""The gear in the 3D scene: each part's mesh under /gear/<part>, posed at the step shown."""

from __future__ import annotations

import numpy as np

from .. import parts as meshes
from .model import SPRING_RESOLUTION, step_index

GEAR = "/gear"  # scene-tree root of the moving parts; nodes are /gear/<part>


def part_node(name: str) -> str:
    return f"{GEAR}/{name}"


def part_color(name: str) -> tuple[int, int, int]:
    try:
        return meshes.PART_COLORS[name]  # knows the other gears' parts too
    except KeyError:
        return (150, 150, 155)


def _same_mesh(a, b) -> bool:
    return a is b or (a[0] is b[0]) or (a[0].shape == b[0].shape and np.array_equal(a[0], b[0])
                                        and np.array_equal(a[1], b[1]))


class GearView:
    """The parts of the result shown (`shown`, a model.Prepared) in `scene` (viser's scene API)."""

    def __init__(self, scene):
        self.scene = scene
        self.handles: dict = {}
        self.shown = None
        self.step = -1  # the step of the revolution the parts are posed at

    def show(self, prepared) -> None:
        """Meshes of a new result: parts the new gear lacks leave, changed ones are replaced
        (re-adding a name replaces only that node), unchanged ones stay."""
        before = self.shown.meshes if self.shown is not None else {}
        for name in [n for n in self.handles if n not in prepared.meshes]:
            self.handles.pop(name).remove()
        for name, mesh in prepared.meshes.items():
            if name in self.handles and name in before and _same_mesh(before[name], mesh):
                continue
            vertices, faces = mesh
            pos, quat = prepared.poses[name]
            self.handles[name] = self.scene.add_mesh_simple(
                part_node(name), vertices, faces, color=part_color(name),
                position=tuple(pos[0]), wxyz=tuple(quat[0]),
                flat_shading=False, side="double" if name == "spring" else "front",
            )
        self.shown = prepared
        self.step = -1  # every part is posed again

    def pose(self, angle: float, force: bool = False) -> int:
        """Pose every part at the step nearest `angle`; returns that step. Parts that never move
        are posed only when forced (a new result)."""
        prepared = self.shown
        n = len(prepared.result.columns["cam_angle_deg"])
        i = step_index(angle, n)
        if i == self.step and not force:
            return i
        for name, (pos, quat) in prepared.poses.items():
            if name in meshes.STATIC_PARTS and not force and self.step >= 0:
                continue
            handle = self.handles.get(name)
            if handle is not None:
                handle.position = pos[i]
                handle.wxyz = quat[i]
        spring = self.handles.get("spring")
        lengths = prepared.spring_lengths
        surge = None if prepared.spring_surge is None else prepared.spring_surge[i]
        # the spring is redrawn when its length changes (or its coils surge), not while it rests
        if spring is not None and (force or self.step < 0 or surge is not None
                                   or abs(float(lengths[i]) - float(lengths[self.step])) > 1e-9):
            spring.vertices = meshes.spring_vertices(prepared.layout, float(lengths[i]), **SPRING_RESOLUTION,
                                                     surge=surge).astype(np.float32)
        self.step = i
        return i
