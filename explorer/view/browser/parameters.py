"""The scene values the browser's fields edit, and what the text of a field means (no viewer).

A field's text becomes a value only when it is a complete quantity of the field's dimension
(issue #28.1): "7 " (a number waiting for its unit) and "7 k" are not yet anything, "7 kg" in
the lash field is not a length. A bare number means the unit the field's label shows (#28.2):
"3000" in "Linkage stiffness [N/mm]" is 3000 N/mm, not the scene files' SI 3000 N/m, so the
value sent to the scene reader always carries its unit.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from typing import Any

from ...core.errors import InputError
from ...core.units import parse_quantity, to_si

# Bounds on what a page may ask for. The page's widgets enforce them too, but any page (or script)
# on the websocket can send any value, so the server checks again. 100 000 steps per revolution
# (28 times the default) take about 1 s and 100 MB; the scene reader's own maxima are far larger.
MAX_GUI_STEPS = 100_000
MAX_TEXT_LENGTH = 100
PAGE = "<page>"  # the "file" a value typed on the page comes from, for explorer.core.units' messages


@dataclass(frozen=True)
class Parameter:
    """One field of the page: a scene key, how it is shown and what its text may be."""

    key: str  # "section.key" of the scene
    label: str
    kind: str  # "choice" | "number" | "integer" | "quantity"
    unit: str = ""  # display unit; a bare number typed into a quantity field means this unit
    dimension: str = ""  # explorer.core.units dimension of a quantity

    @property
    def title(self) -> str:
        """The label on the page: a quantity's names its unit."""
        return f"{self.label} [{self.unit}]" if self.kind == "quantity" else self.label


PARAMETERS: dict[str, Parameter] = {p.key: p for p in (
    Parameter("lift.law", "Lift law", "choice"),
    Parameter("drive.rpm", "Camshaft rpm", "number", "rpm"),
    Parameter("valve.lash", "Lash", "quantity", "mm", "length"),
    Parameter("linkage.stiffness", "Linkage stiffness", "quantity", "N/mm", "stiffness"),
    Parameter("spring.preload", "Spring preload", "quantity", "N", "force"),
    Parameter("spring.rate", "Spring rate", "quantity", "N/mm", "stiffness"),
    Parameter("solver.steps_per_revolution", "Steps / revolution", "integer"),
)}


class NotYet(ValueError):
    """The text is not a value (yet). `typing`: it reads as a value being typed (a number
    followed by a space, waiting for its unit): no error is shown for it, it waits."""

    def __init__(self, reason: str, typing: bool = False):
        super().__init__(reason)
        self.typing = typing


def field_value(parameter: Parameter, value: Any, options: tuple[str, ...] = (), final: bool = False):
    """The value a field's content stands for, as the scene reader takes it: a number, a law
    name, or a quantity's text with its unit ("3000 N/mm" for a bare "3000"). Raises NotYet
    when it is not one: out of bounds, not a quantity of the field's dimension, or unfinished.
    `final`: the user said it is finished (Enter): "7 " is 7 in the field's unit."""
    kind = parameter.kind
    if kind in ("number", "integer"):
        if isinstance(value, bool):
            raise NotYet(f"not a number: {value!r}")
        try:
            number = float(value)
        except (TypeError, ValueError, OverflowError):
            raise NotYet(f"not a number: {str(value)[:MAX_TEXT_LENGTH]!r}") from None
        if not math.isfinite(number):
            raise NotYet(f"not a finite number: {value!r}")
        if kind == "number":
            return number
        if number > MAX_GUI_STEPS:
            raise NotYet(f"at most {MAX_GUI_STEPS} in the explorer, got {number:.6g}")
        return int(number) if number.is_integer() else number
    text = str(value)
    if len(text) > MAX_TEXT_LENGTH:
        raise NotYet(f"longer than {MAX_TEXT_LENGTH} characters")
    if kind == "choice":
        if text not in options:
            raise NotYet(f"not one of the choices: {text!r}")
        return text
    return quantity_text(parameter, text.strip() if final else text)


def quantity_text(parameter: Parameter, text: str) -> str:
    """`text` as a complete quantity of the parameter's dimension, with its unit."""
    stripped = text.strip()
    if not stripped:
        raise NotYet("empty", typing=True)
    if text != text.rstrip():
        raise NotYet(f"{stripped!r} waits for its unit", typing=True)
    try:
        _, unit = parse_quantity(stripped, file=PAGE, key=parameter.title)
        complete = stripped if unit else f"{stripped} {parameter.unit}"
        to_si(complete, parameter.dimension, file=PAGE, key=parameter.title)
    except InputError as exc:
        raise NotYet(exc.reason) from None
    return complete


def override(key: str, value: Any) -> str:
    """A "section.key=value" override whose value the TOML reader reads back unchanged."""
    if isinstance(value, bool):
        return f"{key}={'true' if value else 'false'}"
    if isinstance(value, (list, tuple)):
        return f"{key}=[{', '.join(json.dumps(str(v)) for v in value)}]"
    if isinstance(value, int):
        return f"{key}={value}"
    if isinstance(value, float):
        return f"{key}={value!r}" if math.isfinite(value) else f"{key}={'nan' if math.isnan(value) else ('inf' if value > 0 else '-inf')}"
    return f"{key}={json.dumps(str(value))}"


def scene_values(scene) -> dict[str, Any]:
    """The scene's current value of each editable parameter, in the fields' display units
    (None where the scene has no such section)."""
    per_si = {"mm": 1e3, "N/mm": 1e-3, "N": 1.0}  # exact factors: no unit registry on this path

    def q(value, unit):
        return None if value is None else f"{value * per_si[unit]:.6g} {unit}"

    return {
        "lift.law": scene.lift.law,
        "drive.rpm": float(scene.drive.rpm),
        "valve.lash": q(scene.valve.lash if scene.valve else None, "mm"),
        "linkage.stiffness": q(scene.linkage.stiffness if scene.linkage else None, "N/mm"),
        "spring.preload": q(scene.spring.preload if scene.spring else None, "N"),
        "spring.rate": q(scene.spring.rate if scene.spring else None, "N/mm"),
        "solver.steps_per_revolution": int(scene.solver.steps_per_revolution),
    }


def user_overrides(overrides) -> dict[str, str]:
    """key -> "key=value" for the overrides the page makes (parameters and effects)."""
    out = {}
    for text in overrides:
        key = text.split("=", 1)[0]
        if key in PARAMETERS or key == "effects":
            out[key] = text
    return out
