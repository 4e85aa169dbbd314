"""Each catalogue effect is a complete object: the component options it writes into a study carry
exactly the value it fitted, read back through the baseline (the same path a diagnosis takes).
A new effect in src/agrobot/diagnosis/effects/ is picked up here without editing this file."""
from __future__ import annotations

from pathlib import Path

import pytest

from agrobot.diagnosis.baseline import baseline_from_study
from agrobot.diagnosis.catalogue import CATALOGUE
from agrobot.diagnosis.plausibility import VehicleContext
from agrobot.identification.vehicle import Vehicle
from agrobot.orchestrator.study import Study

ROOT = Path(__file__).resolve().parents[1]
# a position reference point other than the antenna is written into a study as the antenna's position: the
# baseline reads it back as the antenna, not as a reference offset
READ_BACK_AS_THE_ANTENNA = {"position_reference"}


@pytest.mark.parametrize("effect", CATALOGUE, ids=lambda e: e.id)
def test_the_study_option_of_an_effect_carries_its_fitted_value(effect):
    for name in ("figure8.toml", "identification.toml"):    # the gyro lives in the identification study
        study = Study.load(ROOT / "studies" / name)
        base = baseline_from_study(study)
        fitted = dict(base.values)
        for p in effect.parameters:                     # a value inside the bounds, away from the baseline
            fitted[p.name] = p.lower + 0.1 * (p.upper - p.lower)
        try:
            options = effect.options(fitted, base.values, base.study)
        except KeyError as why:     # no study option (a correction of the recording): it says what to do instead
            assert len(str(why)) > 20 and any(w in str(why) for w in ("log", "shift", "lookup", "divide")), why
            return
        if {role for role, _, _ in options} <= set(base.components):
            break
    else:
        pytest.fail(f"no shipped study has the components of {effect.id}'s options {options}")
    extended = study.with_values({f"{base.components[role]}.{name}": value for role, name, value in options})
    again = baseline_from_study(extended).values
    if effect.id in READ_BACK_AS_THE_ANTENNA:
        moved = {name: value for role, name, value in options if role == "yaw_plant"}
        assert again["antenna_forward"] == pytest.approx(moved["antenna_forward"]) if "antenna_forward" in again \
            else extended.parameters(base.components["yaw_plant"])["antenna_forward"] == pytest.approx(
                moved["antenna_forward"])
        return
    for p in effect.parameters:
        assert again[p.name] == pytest.approx(fitted[p.name], rel=1e-9, abs=1e-12), p.name
    untouched = set(base.values) - {p.name for p in effect.parameters} - {"cornering_reference_speed"}
    assert {k: again[k] for k in untouched} == {k: base.values[k] for k in untouched}


@pytest.mark.parametrize("effect", CATALOGUE, ids=lambda e: e.id)
def test_an_effect_is_material_far_from_the_baseline_and_not_at_it(effect):
    base = baseline_from_study(Study.load(ROOT / "studies" / "figure8.toml")).values
    assert not effect.material(base, base)
    assert effect.stages and all(s in ("steering", "yaw", "position", "speed") for s in effect.stages)
    assert all(len(start) == len(effect.parameters) for start in effect.starts)


@pytest.mark.parametrize("effect", CATALOGUE, ids=lambda e: e.id)
def test_an_effect_judges_its_starting_values_plausible_on_every_vehicle_class(effect):
    """Its rule (``Effect.plausibility``, the default passes everything) returns reasons as text and
    none for the values the search starts from, on a tractor and a car, with and without an outline."""
    for table in ({"class": "tractor", "length": 5.0, "width": 2.5}, {"class": "car"}, {}):
        ctx = VehicleContext(Vehicle.from_table(table), 2.9, 1.4, 2.0)
        for start in effect.starts:
            reasons = effect.plausibility(dict(zip((p.name for p in effect.parameters), start)), ctx)
            assert reasons == [], (table, start, reasons)
