"""The exported controller FMU follows the FMI 2.0 / 3.0 co-simulation semantics on its own, driven
through fmpy's API as any standard master drives it: get after set recomputes at a sample instant,
outputs hold between instants, communication steps that divide the period work and others are
refused, ModelStructure lists exactly the dependencies the code has (found by perturbing each
input), initial outputs follow the parameters, the call sequence and non-finite inputs are checked
with logger messages, units carry BaseUnits, only the FMI API leaves the binary and source builds
honour the function prefix."""
from __future__ import annotations

import re
import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module", params=[2, 3])
def exported(request, tmp_path_factory):
    out = tmp_path_factory.mktemp(f"fmi{request.param}") / "guidance_controller.fmu"
    res = subprocess.run([sys.executable, "-m", "agrobot", "export-controller", "studies/figure8.toml",
                          "--out", str(out), "--fmi-version", str(request.param)], cwd=ROOT, capture_output=True,
                         text=True)
    assert res.returncode == 0, res.stderr
    return request.param, out


class Driver:
    """One instance of the FMU through fmpy, with names instead of value references."""

    def __init__(self, fmu: Path) -> None:
        from fmpy import extract, read_model_description
        from fmpy.fmi2 import FMU2Slave
        from fmpy.fmi3 import FMU3Slave

        self.md = md = read_model_description(str(fmu))
        self.fmi3 = md.fmiVersion.startswith("3")
        self.vr = {v.name: v.valueReference for v in md.modelVariables}
        self.inputs = [v.name for v in md.modelVariables if v.causality == "input"]
        self.outputs = [v.name for v in md.modelVariables if v.causality == "output"]
        cls = FMU3Slave if self.fmi3 else FMU2Slave
        self.s = cls(guid=md.instantiationToken if self.fmi3 else md.guid, unzipDirectory=extract(str(fmu)),
                     modelIdentifier=md.coSimulation.modelIdentifier, instanceName="ctl")
        self.s.instantiate()

    def init(self, t0: float = 0.0) -> None:
        if self.fmi3:
            self.s.enterInitializationMode(startTime=t0)
        else:
            self.s.setupExperiment(startTime=t0)
            self.s.enterInitializationMode()

    def set(self, **values) -> None:
        (self.s.setFloat64 if self.fmi3 else self.s.setReal)([self.vr[k] for k in values], list(values.values()))

    def get(self, *names) -> np.ndarray:
        return np.asarray((self.s.getFloat64 if self.fmi3 else self.s.getReal)([self.vr[n] for n in names]))

    def step(self, t: float, h: float) -> None:
        self.s.doStep(t, h)

    def close(self) -> None:
        try:
            self.s.terminate()
        except Exception:  # noqa: BLE001
            pass
        self.s.freeInstance()


def _running(fmu: Path, rng, warm: int = 3) -> tuple[Driver, dict]:
    d = Driver(fmu)
    d.init()
    d.s.exitInitializationMode()
    # a tractor near its reference, driving east at 1.9 m/s: no limit active
    nominal = {"tracker_x_ref": 10.05, "tracker_y_ref": 5.03, "tracker_xdot_ref": 2.0, "tracker_ydot_ref": 0.05,
               "tracker_yaw_rate_ref": 0.01, "tracker_lateral_velocity": 0.0, "tracker_x": 10.0, "tracker_y": 5.0,
               "tracker_heading": 0.02,
               "mpc_yaw_rate": 0.02, "mpc_steer_angle": 0.01, "speed_controller_speed": 1.9,
               "speed_controller_pedal_position": 0.55}
    base = {n: nominal[n] + float(rng.normal(0, 0.005)) for n in d.inputs}
    for k in range(warm):                      # the MPC's state is started (its measured-input branch)
        d.set(**base)
        d.step(k * 0.05, 0.05)
    return d, base


def test_get_after_set_recomputes_at_a_sample_instant_and_holds_between(exported):
    _, fmu = exported
    d, base = _running(fmu, np.random.default_rng(1))
    t = 3 * 0.05
    d.set(**base)
    a = d.get("mpc_steer_angle_cmd", "tracker_error_x")
    d.set(tracker_x=base["tracker_x"] + 0.02)
    b = d.get("mpc_steer_angle_cmd", "tracker_error_x")
    assert b[1] == pytest.approx(a[1] - 0.02, abs=1e-12) and b[0] != a[0]
    d.set(tracker_x=base["tracker_x"])           # back: the same sample again, nothing committed in between
    np.testing.assert_array_equal(d.get("mpc_steer_angle_cmd", "tracker_error_x"), a)
    d.step(t, 0.01)                              # inside the period: outputs hold whatever the inputs
    d.set(tracker_x=base["tracker_x"] + 5.0)
    np.testing.assert_array_equal(d.get("mpc_steer_angle_cmd", "tracker_error_x"), a)
    d.close()


def test_communication_steps_that_do_not_divide_the_period_are_refused_with_a_message(exported, capsys):
    _, fmu = exported
    d, base = _running(fmu, np.random.default_rng(2))
    with pytest.raises(Exception, match="DoStep"):
        d.step(0.15, 0.03)
    assert "is neither a whole multiple of the sample period 0.05 s nor divides it" in capsys.readouterr().out
    with pytest.raises(Exception, match="DoStep"):
        d.step(0.5, 0.05)                        # not where the last step ended
    assert "last step ended at t = 0.15" in capsys.readouterr().out
    d.close()


def test_call_sequence_and_non_finite_inputs_give_an_error_status_and_a_message(exported, capsys):
    _, fmu = exported
    d = Driver(fmu)
    with pytest.raises(Exception):
        d.step(0.0, 0.05)                        # before initialisation
    assert "doStep is not allowed in instantiated mode" in capsys.readouterr().out
    d.init()
    with pytest.raises(Exception):
        d.set(mpc_yaw_rate=float("nan"))
    assert "mpc_yaw_rate = nan refused" in capsys.readouterr().out
    with pytest.raises(Exception):
        d.set(tracker_x=float("inf"))
    assert "tracker_x = inf refused" in capsys.readouterr().out
    with pytest.raises(Exception):
        d.set(mpc_steer_angle_cmd=0.1)
    assert "mpc_steer_angle_cmd is an output" in capsys.readouterr().out
    d.s.exitInitializationMode()
    d.step(0.0, 0.05)
    d.s.terminate()
    with pytest.raises(Exception):
        d.step(0.05, 0.05)
    assert "doStep is not allowed in terminated mode" in capsys.readouterr().out
    d.s.freeInstance()


def test_model_structure_lists_exactly_the_dependencies_the_code_has(exported):
    """Perturb each input alone at one sample instant (get after set, nothing committed) and see
    which outputs move: the declared dependencies, no more and no fewer."""
    version, fmu = exported
    d, base = _running(fmu, np.random.default_rng(3))
    by_vr = {v.valueReference: v.name for v in d.md.modelVariables}
    declared = {u.variable.name: {dep.name for dep in u.dependencies} for u in d.md.outputs}
    d.set(**base)
    ref = d.get(*d.outputs)
    observed = {o: set() for o in d.outputs}
    for name in d.inputs:
        d.set(**{name: base[name] + 0.01})
        moved = np.abs(d.get(*d.outputs) - ref) > 1e-12
        for o, m in zip(d.outputs, moved):
            if m:
                observed[o].add(name)
        d.set(**{name: base[name]})
    # the solver's status is a flag (1: solved) that small moves do not change; it comes from the
    # same QP as the steering command
    assert declared.pop("mpc_qp_status") == declared["mpc_steer_angle_cmd"]
    observed.pop("mpc_qp_status")
    assert observed == declared
    assert by_vr                                   # value references resolved the names
    d.close()


def test_initial_outputs_follow_the_parameters(exported):
    _, fmu = exported
    for neutral in (6.0, 5.2):
        d = Driver(fmu)
        d.set(speed_controller_neutral_voltage=neutral)
        d.init()
        # all inputs zero: no speed error, so the valve sits at its neutral voltage
        assert d.get("speed_controller_pedal_valve_voltage")[0] == pytest.approx(neutral)
        d.s.exitInitializationMode()
        d.close()


def test_units_carry_base_units_and_the_description_is_plain(exported):
    _, fmu = exported
    xml = zipfile.ZipFile(fmu).read("modelDescription.xml").decode()
    assert "np.float64" not in xml and "Sampled" not in xml and "VendorAnnotations" not in xml
    units = dict(re.findall(r'<Unit name="([^"]+)"><BaseUnit ([^/]*)/>', xml))
    assert units["rad/s"] == 's="-1" rad="1"'
    assert units["m/s"] == 'm="1" s="-1"'
    assert units["V"] == 'kg="1" m="2" s="-3" A="-1"'
    assert units["rad"] == 'rad="1"'
    from fmpy.validation import validate_fmu

    assert validate_fmu(str(fmu)) == []


def _extract(fmu: Path, where: Path) -> Path:
    with zipfile.ZipFile(fmu) as zf:
        zf.extractall(where)
    return where


def test_only_the_fmi_api_leaves_the_binary(exported, tmp_path):
    version, fmu = exported
    root = _extract(fmu, tmp_path / "x")
    binary = next((root / "binaries").rglob("*.so"))
    symbols = subprocess.run(["nm", "-D", "--defined-only", str(binary)], capture_output=True, text=True).stdout
    names = [line.split()[-1] for line in symbols.splitlines() if line.strip()]
    assert names and all(n.startswith(f"fmi{version}") for n in names), [n for n in names if not n.startswith("fmi")]
    ldd = subprocess.run(["ldd", str(binary)], capture_output=True, text=True).stdout
    assert "python" not in ldd.lower()


def test_two_source_fmus_link_into_one_library_with_their_prefixes(exported, tmp_path):
    """Source-code FMUs compiled with FMI2_FUNCTION_PREFIX / FMI3_FUNCTION_PREFIX: two of them (here
    the same controller twice, as two models would be) link together without a clash."""
    version, fmu = exported
    root = _extract(fmu, tmp_path / "x")
    objects = []
    for prefix in ("left_", "right_"):
        obj = tmp_path / f"{prefix}.o"
        subprocess.run(["gcc", "-c", "-O1", "-fPIC", f"-DFMI{version}_FUNCTION_PREFIX={prefix}",
                        "-I", str(root / "sources"), str(root / "sources/guidance_controller.c"), "-o", str(obj)],
                       check=True)
        objects.append(str(obj))
    lib = tmp_path / "both.so"
    res = subprocess.run(["gcc", "-shared", "-o", str(lib), *objects, "-lm"], capture_output=True, text=True)
    assert res.returncode == 0, res.stderr
    symbols = subprocess.run(["nm", "--defined-only", str(lib)], capture_output=True, text=True).stdout
    assert f"left_fmi{version}DoStep" in symbols and f"right_fmi{version}DoStep" in symbols
    assert "agrobot_qp_solve" not in re.sub(r"\b[tbdr] \S+", "", symbols)      # only local symbols besides the API


# the FMI 2.0 co-simulation API (the standard's fmi2Functions.h: common and co-simulation functions)
FMI2_CS_API = ("GetTypesPlatform", "GetVersion", "SetDebugLogging", "Instantiate", "FreeInstance", "SetupExperiment",
               "EnterInitializationMode", "ExitInitializationMode", "Terminate", "Reset", "GetReal", "GetInteger",
               "GetBoolean", "GetString", "SetReal", "SetInteger", "SetBoolean", "SetString", "GetFMUstate",
               "SetFMUstate", "FreeFMUstate", "SerializedFMUstateSize", "SerializeFMUstate", "DeSerializeFMUstate",
               "GetDirectionalDerivative", "SetRealInputDerivatives", "GetRealOutputDerivatives", "DoStep",
               "CancelStep", "GetStatus", "GetRealStatus", "GetIntegerStatus", "GetBooleanStatus", "GetStringStatus")


def test_the_fmi2_wrapper_defines_every_function_of_the_co_simulation_api():
    """Read from the wrapper's source, without compiling: each function is defined, written out or
    made by its NO_VARIABLES(kind, type) macro (fmi2Get<kind> and fmi2Set<kind>)."""
    source = (ROOT / "src/agrobot/fmu_export/c/fmi2_cs.c").read_text(encoding="utf-8")
    defined = set(re.findall(r"^(?:const\s+)?\w+\s*\*?\s*fmi2(\w+)\s*\(", source, flags=re.M))
    for kind in re.findall(r"^NO_VARIABLES\((\w+),", source, flags=re.M):
        defined |= {f"Get{kind}", f"Set{kind}"}
    assert not [f for f in FMI2_CS_API if f not in defined], sorted(defined)
