"""Effect 'gear': what is particular to the scene's gear, along the cycle (its `report`:
explorer.gears.base.Gear, item 8), under the summary's "gear" block with the gear's type.

The contact statics of the roller gears and the rolling lever (pressure angle referred to the
lever, self-locking margin, normal force, camshaft torque, Hertz stress, cam width) are the
'contact' effect's, from each gear's contact geometry.
"""

from __future__ import annotations

from ..result import EffectOutput


def gear_effect(ctx) -> EffectOutput:
    out = ctx.gear.report(ctx)
    return EffectOutput(columns=out.columns, summary={"gear": {"type": ctx.gear.type, **out.summary}},
                        events=out.events, warnings=out.warnings)
