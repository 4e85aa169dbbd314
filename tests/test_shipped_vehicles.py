"""The shipped studies say what vehicle they are: a log diagnosed or identified against one is judged
against that vehicle's class and outline, and the [vehicle] wheelbase is the plant's l_f + l_r.

Independent truths: the two declarations of a study (its [vehicle] table and its plant's axles,
defaults resolved) must agree; the classes and outlines are those of the vehicles the studies
model (the paper's tractor, a mid-size car, a 1:10 F1TENTH car)."""
from __future__ import annotations

import pytest

from agrobot.identification.vehicle import Vehicle
from agrobot.orchestrator.resolver import resolve
from agrobot.orchestrator.study import load_study
from agrobot.studies import shipped

AGREE = 0.01          # relative: the [vehicle] wheelbase and the plant's l_f + l_r
# the studies a user diagnoses or identifies against, and the class each must declare
USED = {"figure8.toml": "tractor", "identification.toml": "tractor", "field_coverage.toml": "tractor",
        "passenger_car.toml": "car", "passenger_car_identification.toml": "car", "f1tenth.toml": "scale_car"}


def plant_wheelbase(study) -> float | None:
    """l_f + l_r of the study's yaw plant (its defaults resolved); None: no yaw plant."""
    resolved = resolve(study)
    names = resolved.find(role="yaw_plant")
    if not names:
        return None
    p = resolved.parameters(names[0])
    return float(p["l_f"]) + float(p["l_r"])


def disagreement(path) -> str | None:
    """What is wrong with a study's [vehicle] wheelbase against its plant (None: they agree, or it
    does not have both)."""
    study = load_study(path)
    declared, plant = Vehicle.of(study).wheelbase, plant_wheelbase(study)
    if declared is None or plant is None or abs(declared / plant - 1) <= AGREE:
        return None
    return f"{path.name}: vehicle.wheelbase = {declared:g} m but the plant's l_f + l_r = {plant:g} m"


def test_every_shipped_wheelbase_is_its_plants():
    paths = sorted(shipped().glob("*.toml"))
    assert len(paths) > 10
    wrong = [w for w in map(disagreement, paths) if w]
    assert not wrong, wrong


def test_a_wheelbase_off_its_plant_is_caught(tmp_path):
    path = tmp_path / "longer.toml"
    path.write_text(f'extends = "{shipped("figure8.toml").as_posix()}"\n[vehicle]\nwheelbase = 1.45\n')
    assert "1.45" in (disagreement(path) or "")
    path.write_text(f'extends = "{shipped("figure8.toml").as_posix()}"\n[vehicle]\nwheelbase = 1.41\n')
    assert disagreement(path) is None


@pytest.mark.parametrize("name", sorted(USED))
def test_used_study_declares_its_class_and_outline(name):
    study = load_study(shipped(name))
    vehicle = Vehicle.of(study)
    assert vehicle.kind == USED[name]
    assert vehicle.wheelbase is not None and vehicle.length is not None and vehicle.width is not None
    # an outline around the axles: longer than the wheelbase, narrower than it is long
    assert vehicle.wheelbase < vehicle.length < 2.5 * vehicle.wheelbase
    assert 0.3 * vehicle.length < vehicle.width < vehicle.length
    assert plant_wheelbase(study) is not None


def test_a_tractor_studys_outline_holds_the_papers_antenna():
    """The paper (section II): the GPS antenna stands straight above the centre of the rear axle."""
    (fwd_lo, fwd_hi), (left_lo, left_hi) = Vehicle.of(load_study(shipped("figure8.toml"))).lever_arm_bounds()
    assert fwd_lo < 0.0 < fwd_hi and left_lo < 0.0 < left_hi
