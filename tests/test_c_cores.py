"""A component is one home: its class declares its C core (the C file beside its module), and every
parameter it declares is accounted for by that core: read by the C (``p[P_name]``), fixed when the code
is generated, or listed as not modelled, in which case the compiled engine and the FMU exporter refuse
a study that sets it, naming it. A parameter added tomorrow that the core ignores fails here."""
from __future__ import annotations

import importlib
import pkgutil
import re
from pathlib import Path

import pytest

import agrobot.components
from agrobot.orchestrator.build import build_system
from agrobot.orchestrator.compiled import CompiledRefused, cores_of, select_engine
from agrobot.orchestrator.compiled.cores import CoreDescription, description_of
from agrobot.orchestrator.resolver import resolve
from agrobot.orchestrator.study import Study

ROOT = Path(__file__).resolve().parents[1]
FIGURE8 = ROOT / "studies" / "figure8.toml"


def _classes_with_cores() -> list[type]:
    found = []
    for info in pkgutil.iter_modules(agrobot.components.__path__):
        cls = getattr(importlib.import_module(f"agrobot.components.{info.name}"), "COMPONENT", None)
        if cls is not None and isinstance(vars(cls).get("c_core"), CoreDescription):
            found.append(cls)
    return found


CLASSES = _classes_with_cores()


def _read_by_the_c(cls) -> set[str]:
    """The parameter names the core's C files read (``P_name``)."""
    text = "".join(f.read_text() for f in cls.c_core.files if f.suffix in (".c", ".h"))
    return set(re.findall(r"\bP_([A-Za-z0-9_]+)", text))


def test_the_shipped_loop_components_have_their_core_beside_them():
    names = {cls.__name__ for cls in CLASSES}
    assert {"TractorYawPlant", "SteeringHydraulics", "SpeedDrivetrain", "GPSSensor", "YawRateMPC", "SpeedPID",
            "KinematicTracker", "PoseEKF", "SpeedKF", "Figure8Reference", "ComputationDelay"} <= names
    components_dir = Path(agrobot.components.__file__).resolve().parent
    for cls in CLASSES:
        source = cls.c_core.source.resolve()
        module = Path(importlib.import_module(cls.__module__).__file__).resolve()
        assert source == module.with_suffix(".c") and source.parent == components_dir, cls.__name__
        assert all(f.exists() for f in cls.c_core.files), cls.__name__


@pytest.mark.parametrize("cls", CLASSES, ids=lambda c: c.__name__)
def test_every_parameter_is_read_by_the_core_fixed_at_generation_or_listed_as_not_compiled(cls):
    description = cls.c_core
    declared = [v.name for v in cls.variables if v.causality == "parameter"]
    read = _read_by_the_c(cls)
    fixed, absent = set(description.compiled_parameters), set(description.not_compiled)
    unaccounted = [n for n in declared if n not in read | fixed | absent]
    assert unaccounted == [], f"{cls.__name__}: parameters its C core ignores without saying so: {unaccounted}"
    assert not (fixed & absent) and not (read & absent), cls.__name__
    assert (fixed | absent) <= set(declared), f"{cls.__name__}: lists undeclared names {sorted((fixed | absent) - set(declared))}"
    own = {n for n, *_ in description.extra_parameters}
    undeclared = {n for n in read if not n.startswith("_")} - set(declared) - own
    assert undeclared == set(), f"{cls.__name__}: its C reads parameters it does not declare: {sorted(undeclared)}"


def _set_values() -> list[tuple[str, str, str]]:
    """(component, parameter, a --set value away from the default) for every parameter not compiled by
    a core of the figure-8 study (those a study can set from the command line)."""
    study = Study.load(FIGURE8)
    system = build_system(resolve(study))
    cases = []
    for name, node in system.nodes.items():
        description = description_of(node.component)
        for parameter in description.not_compiled if description else ():
            start = node.component.declared("parameter")[parameter].start
            if isinstance(start, bool) or not isinstance(start, (int, float)):
                continue                           # files, lists and names: their own tests set them
            cases.append((name, parameter, repr(float(start) * 1.5 + 0.25)))
    return cases


@pytest.mark.parametrize("component, parameter, value", _set_values())
def test_the_compiled_engine_refuses_a_study_that_sets_what_its_core_does_not_model(component, parameter, value):
    system = build_system(resolve(Study.load(FIGURE8, [f"{component}.{parameter}={value}"])))
    with pytest.raises(CompiledRefused, match=rf"{component} \({re.escape(parameter)} = .* has no C form: its core "):
        select_engine(system, "compiled")
    factory, note = select_engine(system, "auto")        # auto runs it in Python and says why
    assert factory.__name__ == "Simulation" and parameter in note


def test_the_default_of_a_not_compiled_parameter_is_what_the_core_runs():
    """Set to its default, a parameter the core does not model changes nothing: the study compiles."""
    system = build_system(resolve(Study.load(FIGURE8, ["tractor.tyre_friction=0.0", "gps.bridging_timeout=1200"])))
    cores, missing = cores_of(system)
    assert missing == {} and set(cores) == set(system.nodes)


def test_a_subclass_with_other_equations_has_no_core_until_it_declares_one():
    from agrobot.components.steering_hydraulics import SteeringHydraulics

    class Slower(SteeringHydraulics):
        pass

    assert description_of(SteeringHydraulics("s", {})) is SteeringHydraulics.c_core
    assert description_of(Slower("s", {})) is None
