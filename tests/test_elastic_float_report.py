"""The elastic valve's float in simulate's summary and warnings, the same in all three elastic
models (massless linkage, spring chain, train of parts), and the not-periodic warning (an expert
audit found the chain's first_separation_deg counting a rebound after landing, no float warning
in any model, and no not-periodic warning from the chain and the train)."""

from __future__ import annotations

import math

import numpy as np
import pytest

import explorer
from explorer import load_scene, simulate
from explorer.scene.builtin import scenes_dir

FLOATS = [  # (scene, rpm): massless, massless without forces, chain, chain, train, train + adjuster
    ("valve_float_demo.toml", 3000), ("elastic_float.toml", 4000), ("spring_surge.toml", 2600),
    ("spring_surge.toml", 2300), ("pushrod_train.toml", 3000), ("finger_hla_pumpup.toml", 4800),
]


@pytest.mark.parametrize("name, rpm", FLOATS)
def test_the_summarys_float_is_the_sweeps(name, rpm):
    # the oracle: the sweep row, whose massless figures come from the compiled kernel's own walk
    # (dynamics/kernel_figures.py: _valve_periods), an independent implementation; 1e-12 rel: the
    # compiled and the Python exact solver agree to round-off (the chain and the train run the same
    # Python solver in both: equal)
    path = scenes_dir() / name
    r = simulate(load_scene(path, [f"drive.rpm={rpm}"]))
    row = explorer.sweep(str(path), vary={"drive.rpm": f"{rpm},{rpm + 1}"}).columns
    s = r.summary
    assert s["float_separations"] == row["separations"][0]
    assert s["float_flight_time_s"] == pytest.approx(row["flight_time_s"][0], rel=1e-12, abs=0.0)
    if s["float_separations"]:
        assert s["first_separation_deg"] == pytest.approx(row["first_separation_deg"][0], rel=1e-12)
        text = [w for w in r.warnings if w.startswith("elastic float")]
        assert len(text) == 1
        assert (f"lost {s['float_separations']} time(s) while the valve is open, first at "
                f"{s['first_separation_deg']:.1f} deg, {1e3 * s['float_flight_time_s']:.3g} ms in flight") in text[0]
        jump = s.get("jump_speed_rpm")  # the forces effect's rigid float speed, where the scene has it
        assert ("below the rigid train's float speed" in text[0]) is (jump is not None and rpm < jump)
    else:
        assert s["first_separation_deg"] is None and math.isnan(row["first_separation_deg"][0])
        assert not any(w.startswith("elastic float") for w in r.warnings)


def test_a_rebound_after_landing_is_no_float():
    # spring_surge at 2300 rpm: the valve lands at 176.83 deg and leaves the linkage on the rebound
    # at 178.29 deg; the summary's first_separation_deg took that rebound (the sweep did not)
    r = simulate(load_scene(scenes_dir() / "spring_surge.toml", ["drive.rpm=2300"]))
    kinds = [(e.kind, round(e.cam_angle_deg, 2)) for e in r.events if e.kind in ("seat", "separation")]
    assert kinds[:2] == [("seat", 176.83), ("separation", 178.29)]
    assert r.summary["first_separation_deg"] is None and r.summary["float_separations"] == 0


@pytest.mark.parametrize("name, rpm", [("spring_surge.toml", 11658), ("pushrod_train.toml", 10091),
                                       ("elastic_float.toml", 20000)])
def test_a_run_that_ends_off_its_seat_says_it_is_not_periodic(name, rpm):
    # far above the float speed the valve is still in the air at the revolution's end (the audit:
    # spring_surge 17.8 mm at 359.9 deg, pushrod_train 5.9 mm): each model says so, the chain and
    # the train (elastic seat: phase code 0 on it) as the massless model did
    r = simulate(load_scene(scenes_dir() / name, [f"drive.rpm={rpm}"]))
    assert r.columns["valve_lift_m"][-1] > 1e-3
    assert any(w.startswith("the valve has not come back to rest on its seat") for w in r.warnings)
    quiet = simulate(load_scene(scenes_dir() / name))  # at their own speeds they close on themselves
    assert not any(w.startswith("the valve has not come back") for w in quiet.warnings)


def test_the_continuous_springs_frequencies_beside_the_chains():
    # Shigley's fixed-fixed spring f_j = (j/2) sqrt(k/m_s) (Shigley's Mechanical Engineering
    # Design, 10th ed., eq. 10-25), by hand from the scene: 30.6 N/mm is its rate; the chain of 8
    # masses lies below it, more for the higher modes (its discretisation)
    scene = load_scene(scenes_dir() / "spring_surge.toml")
    r = simulate(scene)
    k, m = scene.spring.rate, r.summary["spring_mass_kg"]
    hand = [0.5 * j * math.sqrt(k / m) for j in range(1, 6)]
    assert r.summary["spring_continuous_frequencies_Hz"] == pytest.approx(hand, rel=1e-14)
    assert hand[0] == pytest.approx(414.03, rel=1e-5)
    chain = np.asarray(r.summary["spring_modal_frequencies_Hz"])
    gap = chain / np.asarray(hand) - 1.0
    assert np.all(gap < 0.0) and np.all(np.diff(gap) < 0.0) and gap[0] == pytest.approx(-0.00507, abs=1e-4)
