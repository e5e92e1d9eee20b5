"""The typed hand-over to the effects: the Protocols of explorer/effects/context.py (the scene as
the effects read it; the effects sit below the scene and may not import it) against the classes
that implement them, so a Protocol cannot declare what the scene does not have."""

from __future__ import annotations

import dataclasses
import inspect
from typing import Protocol, runtime_checkable

import pytest

from explorer import load_scene
from explorer.dynamics.hla import HLA
from explorer.effects import context
from explorer.gears.base import Gear
from explorer.scene import scene as sc
from explorer.scene.train_section import HLASection

from conftest import SCENES

# Protocol -> the class that implements it, and the Scene field that holds one (None: the scene)
PAIRS = [
    (context.SceneView, sc.Scene, None),
    (context.DriveView, sc.Drive, "drive"),
    (context.FollowerView, sc.Follower, "follower"),
    (context.ValveView, sc.Valve, "valve"),
    (context.SpringView, sc.Spring, "spring"),
    (context.LoadsView, sc.Loads, "loads"),
    (context.LinkageView, sc.Linkage, "linkage"),
    (context.SeatView, sc.Seat, "seat"),
    (context.SolverView, sc.Solver, "solver"),
    (context.HLAView, HLASection, "hla"),
]


def members(protocol) -> list[str]:
    return [name for name, value in vars(protocol).items()
            if not name.startswith("_") and (isinstance(value, property) or inspect.isfunction(value))]


def has(cls, name: str) -> bool:
    return name in {f.name for f in dataclasses.fields(cls)} or hasattr(cls, name)


@pytest.mark.parametrize("protocol, cls, field", PAIRS, ids=[p.__name__ for p, _, _ in PAIRS])
def test_every_member_of_a_protocol_is_on_its_class(protocol, cls, field):
    assert members(protocol), protocol
    missing = [name for name in members(protocol) if not has(cls, name)]
    assert not missing, f"{protocol.__name__} declares what {cls.__name__} does not have: {missing}"
    if field is not None:  # the scene's section of that name is declared as this Protocol
        assert field in members(context.SceneView)
        assert protocol.__name__ in str(context.SceneView.__dict__[field].fget.__annotations__["return"])


def test_the_gear_hooks_are_on_the_gear_base():
    missing = [name for name in members(context.GearHooks) + ["type", "batch_sweeps", "columns"]
               if not hasattr(Gear, name)]
    assert not missing


def test_the_checker_sees_a_member_the_class_lacks():
    class Planted(context.DriveView, Protocol):
        @property
        def gear_ratio(self) -> float: ...

    assert [n for n in members(Planted) if not has(sc.Drive, n)] == ["gear_ratio"]


@pytest.mark.parametrize("path", sorted(SCENES.glob("*.toml")), ids=lambda p: p.stem)
def test_every_builtin_scene_and_its_sections_are_what_the_effects_read(path):
    scene = load_scene(path)
    assert isinstance(scene, runtime_checkable(context.SceneView))
    for protocol, _, field in PAIRS[1:]:
        section = getattr(scene, field)
        if section is not None:
            assert isinstance(section, runtime_checkable(protocol)), (path.name, field)
    if scene.hla is not None:
        assert isinstance(scene.hla.hla, HLA)
