"""One rule for --out in every command (orchestrator.output), walked verb by verb: a foreign
folder is refused and kept, an earlier result is replaced only with --overwrite, an input is never
an output, one writer at a time by a lock that leaves nothing behind, staging folders of killed
commands are removed, a full disk is a named error; the flags every verb shares."""
from __future__ import annotations

import errno
import json
from pathlib import Path

import pandas as pd
import pytest

from agrobot.orchestrator.cli import build_parser, main
from agrobot.orchestrator.component import Component, out, par
from agrobot.orchestrator.output import OutputLock
from tests.commands import in_process as _cli

ROOT = Path(__file__).resolve().parent.parent
FIELD = ROOT / "studies" / "fields" / "test_parcel.json"

TOY = """[study]
name = "toy"
stop_time = 1.0
base_step = 0.05
seed = 1
signals_format = "csv"

[components.f]
type = "tests.toy_components:FailAt"
parameters = {{ fail_time = 5.0 }}
{extra}"""

SWEEP = """
[sweep]
parameters = { "f.fail_time" = [5.0, 6.0] }
"""


class Recorder(Component):
    """Writes a line per step to ``record_file`` (an output-like parameter)."""

    sampled = True
    variables = (par("record_file", "", "", "file it writes"), out("value", "s", 0.0, "t"))

    def initialize(self, t0, dt):
        self.file = open(self.p["record_file"], "a") if self.p["record_file"] else None

    def step(self, t, dt):
        self.y["value"] = t
        if self.file:
            self.file.write(f"{t}\n")

    def terminate(self):
        if self.file:
            self.file.close()


def _study(tmp_path: Path, extra: str = "", name: str = "toy.toml") -> Path:
    path = tmp_path / name
    path.write_text(TOY.format(extra=extra))
    return path


def _log(tmp_path: Path) -> Path:
    t = [0.1 * k for k in range(50)]
    path = tmp_path / "log.csv"
    pd.DataFrame({"t": t, "x": t, "y": [0.0] * 50}).to_csv(path, index=False)
    return path


# verb -> (argv without --out, the folder (or file) --out names, what marks an earlier result of the verb)
def _verbs(tmp_path: Path) -> dict[str, tuple[list, str, str]]:
    study = _study(tmp_path)
    sweep = _study(tmp_path, SWEEP, "sweep.toml")
    log = _log(tmp_path)
    f8 = tmp_path / "f8.toml"
    f8.write_text((ROOT / "studies" / "figure8.toml").read_text())
    return {
        "run": (["run", study], "out_run", "run.json"),
        "sweep": (["sweep", sweep, "--workers", "1"], "out_sweep", "sweep.json"),
        "margins": (["margins", f8], "out_margins", "margins.json"),
        "tune": (["tune", f8, "--no-simulation"], "tuned.toml", None),
        "diagnose": (["diagnose", log], "out_diagnose", "diagnosis.json"),
        "plan": (["plan", FIELD], "out_plan", "plan.json"),
        "fields": (["fields", FIELD], "out_fields", "fields.json"),
        "identify": (["identify", log], "out_identify", "identification.json"),
        "convert": (["convert", log], "converted.csv", None),
        "export-controller": (["export-controller", f8], "c.fmu", None),
        "export-ssp": (["export-ssp", f8], "s.ssp", None),
        "emulate": (["emulate", ROOT / "studies" / "tractor_emulator.toml", "--nmea-port", "0"], "out_emulate",
                    "run.json"),
    }


def test_every_verb_has_the_shared_flags_and_the_program_a_version(capsys):
    parser = build_parser()
    verbs = parser._subparsers._group_actions[0].choices
    assert set(verbs) >= {"run", "sweep", "margins", "tune", "diagnose", "plan", "fields", "identify", "convert",
                          "export-controller", "export-ssp", "emulate"}
    for name, sub in verbs.items():
        flags = {o for a in sub._actions for o in a.option_strings}
        assert {"--out", "--overwrite", "--quiet", "--no-progress"} <= flags, name
    with pytest.raises(SystemExit) as done:
        main(["--version"])
    assert done.value.code == 0 and capsys.readouterr().out.split()[-3].count(".") >= 1
    margins = {o for a in verbs["margins"]._actions for o in a.option_strings}
    assert "--simulate" in margins and "--no-simulation" not in margins


def _leftovers(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir() if p.name.startswith("."))


def test_every_verb_refuses_a_foreign_folder_an_input_a_busy_out_and_an_unasked_replacement(tmp_path, capsys):
    """Checked before any work: each refusal exits 2 naming what is there, and leaves the folder
    and its neighbours as they were (no lock file, no staging folder)."""
    for verb, (argv, name, signature) in _verbs(tmp_path).items():
        target = tmp_path / name
        if signature is not None:           # a folder verb
            target.mkdir()
            (target / "precious.txt").write_text("mine")
            for extra in ([], ["--overwrite"]):
                code, _, err = _cli(argv + ["--out", target] + extra, capsys)
                assert code == 2 and "precious.txt" in err and "Traceback" not in err, (verb, err)
            assert (target / "precious.txt").read_text() == "mine" and len(list(target.iterdir())) == 1
            (target / "precious.txt").unlink()
            (target / signature).write_text("{}")             # an earlier result of this verb
            code, _, err = _cli(argv + ["--out", target], capsys)
            assert code == 2 and "--overwrite" in err and signature in err, (verb, err)
            assert (target / signature).read_text() == "{}"
        else:                               # a file verb
            target.write_text("mine")
            code, _, err = _cli(argv + ["--out", target], capsys)
            assert code == 2 and "exists" in err and "--overwrite" in err, (verb, err)
            assert target.read_text() == "mine"
            target.unlink()
        # the input itself, or a folder holding it, is never an output (--overwrite or not)
        given = Path(argv[1])
        for bad in ([given] if signature is None and given.suffix == Path(name).suffix else []) + [given.parent]:
            if signature is None and bad.is_dir():
                continue
            code, _, err = _cli(argv + ["--out", bad, "--overwrite"], capsys)
            assert code == 2 and "input" in err, (verb, bad, err)
        # one writer at a time
        with OutputLock(tmp_path / f"busy_{name}"):
            code, _, err = _cli(argv + ["--out", tmp_path / f"busy_{name}"], capsys)
        assert code == 2 and "is writing to it" in err, (verb, err)
    assert not _leftovers(tmp_path), _leftovers(tmp_path)


def test_the_input_is_never_the_output(tmp_path, capsys):
    """convert raw.csv --out raw.csv; tune S.toml --out S.toml; run proj/s.toml --out proj; an --out
    inside a recording's folder: refused, the input intact."""
    log = _log(tmp_path)
    before = log.read_bytes()
    code, _, err = _cli(["convert", log, "--out", log, "--overwrite"], capsys)
    assert code == 2 and "is the input" in err and log.read_bytes() == before
    base = tmp_path / "base.toml"
    base.write_text((ROOT / "studies" / "figure8.toml").read_text())
    child = tmp_path / "child.toml"
    child.write_text(f'extends = "{base.name}"\n')
    for study in (base, child):              # the file itself, and a file it extends
        code, _, err = _cli(["tune", child, "--out", study, "--overwrite", "--no-simulation"], capsys)
        assert code == 2 and "is the input" in err, err
    assert base.read_text() == (ROOT / "studies" / "figure8.toml").read_text()
    proj = tmp_path / "proj"
    proj.mkdir()
    study = _study(proj)
    code, _, err = _cli(["run", study, "--out", proj, "--overwrite"], capsys)
    assert code == 2 and "holds the input" in err and study.exists()
    folder = tmp_path / "rec"
    folder.mkdir()
    (folder / "a.csv").write_bytes(before)
    code, _, err = _cli(["convert", folder, "--out", folder / "sub" / "x.csv"], capsys)
    assert code == 2 and "inside the input" in err and not (folder / "sub").exists()


def test_a_run_is_written_replaced_only_with_overwrite_and_leaves_nothing_beside(tmp_path, capsys):
    study = _study(tmp_path)
    out = tmp_path / "res"
    code, _, err = _cli(["run", study, "--out", out, "--quiet"], capsys)
    assert code == 0, err
    assert (out / "run.json").exists() and not _leftovers(tmp_path)
    (out / "extra.txt").write_text("from the first run's user")
    code, _, err = _cli(["run", study, "--out", out], capsys)
    assert code == 2 and "--overwrite" in err and (out / "extra.txt").exists()
    code, printed, err = _cli(["run", study, "--out", out, "--overwrite"], capsys)
    assert code == 0 and "results written" in printed, err
    assert not (out / "extra.txt").exists() and json.loads((out / "metrics.json").read_text())["status"] == "completed"
    assert not _leftovers(tmp_path)


def test_quiet_prints_nothing_but_the_files_are_written(tmp_path, capsys):
    study = _study(tmp_path)
    code, printed, err = _cli(["run", study, "--out", tmp_path / "q", "--quiet"], capsys)
    assert code == 0 and printed == "" and (tmp_path / "q" / "signals.csv").exists(), err


def test_staging_folders_of_a_killed_run_are_removed_by_the_next(tmp_path, capsys):
    study = _study(tmp_path)
    stale = tmp_path / ".res.staging-k1ll3d"
    stale.mkdir()
    (stale / "signals.csv").write_text("t\n0\n")
    (tmp_path / ".res.lock").write_text("")              # the lock file of a killed run: no lock held
    unrelated = tmp_path / ".res2.staging-abcdef"         # another --out's: not ours to remove
    unrelated.mkdir()
    code, _, err = _cli(["run", study, "--out", tmp_path / "res"], capsys)
    assert code == 0, err
    assert not stale.exists() and stale.name in err and unrelated.exists()
    assert not (tmp_path / ".res.lock").exists()


def test_a_full_disk_is_named_and_the_earlier_result_kept(tmp_path, capsys, monkeypatch):
    from agrobot.orchestrator import atomic_files

    study = _study(tmp_path)
    out = tmp_path / "res"
    assert _cli(["run", study, "--out", out], capsys)[0] == 0
    before = (out / "signals.csv").read_bytes()

    def full(self, block):
        raise OSError(errno.ENOSPC, "No space left on device", str(self.path))

    monkeypatch.setattr(atomic_files.SignalWriter, "append", full)
    code, _, err = _cli(["run", study, "--out", out, "--overwrite"], capsys)
    assert code == 2 and "disk is full" in err and "signals.csv" in err and "Traceback" not in err, err
    assert (out / "signals.csv").read_bytes() == before and not _leftovers(tmp_path)
    # a command that writes a file: the same
    log = _log(tmp_path)
    monkeypatch.setattr(atomic_files.pd.DataFrame, "to_csv", lambda *a, **k: (_ for _ in ()).throw(
        OSError(errno.ENOSPC, "No space left on device")))
    code, _, err = _cli(["convert", log, "--out", tmp_path / "c.csv"], capsys)
    assert code == 2 and "disk is full" in err and not (tmp_path / "c.csv").exists(), err
    assert not _leftovers(tmp_path)


def test_an_output_parameter_outside_out_needs_the_command_line(tmp_path, capsys):
    extra = '\n[components.r]\ntype = "tests.test_command_rules:Recorder"\nparameters = {{ record_file = "{}" }}\n'
    victim = tmp_path / "victim.txt"
    victim.write_text("keep me\n")
    study = _study(tmp_path, extra.format(victim), "rec.toml")
    code, _, err = _cli(["run", study, "--out", tmp_path / "o1"], capsys)
    assert code == 2 and "writes outside --out" in err and "record_file" in err, err
    assert victim.read_text() == "keep me\n"
    code, _, err = _cli(["run", study, "--out", tmp_path / "o2", "--set", f"r.record_file={victim}", "--overwrite"],
                        capsys)
    assert code == 0 and victim.read_text().startswith("0.0"), err      # a written file: replaced, with --overwrite
    inside = tmp_path / "o3" / "nmea" / "rec.txt"          # inside --out: goes with the result
    study = _study(tmp_path, extra.format(inside), "rec3.toml")
    code, _, err = _cli(["run", study, "--out", tmp_path / "o3"], capsys)
    assert code == 0 and len(inside.read_text().split()) == round(1.0 / 0.05) + 1, err   # t = 0, 0.05 .. 1
    study = _study(tmp_path, extra.format(tmp_path / "rec3.toml"), "rec4.toml")   # the study it ran: never
    code, _, err = _cli(["run", study, "--out", tmp_path / "o4", "--set", f"r.record_file={tmp_path / 'rec4.toml'}"],
                        capsys)
    assert code == 2 and "input" in err


def test_sweeps_share_the_lock_and_never_replace_a_completed_point(tmp_path, capsys):
    from agrobot.orchestrator.study import load_study
    from agrobot.orchestrator.sweep import SweepRun, expand

    sweep = _study(tmp_path, SWEEP, "sweep.toml")
    out = tmp_path / "sw"
    with OutputLock(out):                 # a run writing there: the sweep waits its turn
        code, _, err = _cli(["sweep", sweep, "--out", out, "--workers", "1"], capsys)
    assert code == 2 and "is writing to it" in err
    runner = SweepRun(load_study(sweep), out)
    runner.validate()
    point = expand(runner.study)[0]
    runner.store(point, {"status": "completed", "metrics": {"m": 1.0}})
    record = runner.store(point, {"status": "failed", "error": "a second sweep's"})
    assert record["status"] == "completed"
    assert json.loads(runner.record_path(point).read_text())["metrics"] == {"m": 1.0}
    code, _, err = _cli(["run", _study(tmp_path), "--out", out, "--overwrite"], capsys)   # a run into a sweep's
    assert code == 2 and "not a run result" in err and runner.record_path(point).exists()


def test_set_reaches_the_sweep_table_a_step_and_lists_with_the_files_types_and_checks(tmp_path, capsys):
    import tomllib

    from agrobot.orchestrator.study import StudyError, load_study
    from agrobot.orchestrator.sweep import expand

    robustness = ROOT / "studies" / "robustness.toml"
    written = tomllib.loads(robustness.read_text())["sweep"]["samples"]
    study = load_study(robustness, ["sweep.samples=5"])
    assert study.sweep.samples == 5 and len(expand(study)) == 5 != written
    assert f"sweep.samples = 5, was {written}" in capsys.readouterr().out
    toy = _study(tmp_path)                              # no [sweep] table: --set starts one
    for item in ("sweep.parameters.f.fail_time=[5, 6, 7]", "sweep.parameters.f.fail_time=5,6,7"):
        study = load_study(toy, [item, "f.step=0.1"])
        assert [p.values for p in expand(study)] == [{"f.fail_time": v} for v in (5, 6, 7)]
        assert study.components["f"].step == 0.1 and "step" not in study.components["f"].parameters
    printed = capsys.readouterr().out.splitlines()
    assert printed[1] == "--set f.step=0.1: components.f.step = 0.1, was not set in the file (the default)"
    with pytest.raises(StudyError, match="not a value a study file could hold"):
        load_study(toy, ["f.fail_time=a,b"])
    # the same check as the file: samples >= 1, said of the --set item
    (tmp_path / "zero.toml").write_text(f'extends = "{robustness.as_posix()}"\n[sweep]\nsamples = 0\n')
    with pytest.raises(StudyError) as from_file:
        load_study(tmp_path / "zero.toml")
    with pytest.raises(StudyError) as from_set:
        load_study(robustness, ["sweep.samples=0"])
    assert "greater than or equal to 1" in str(from_file.value) and "greater than or equal to 1" in str(from_set.value)
    assert str(from_set.value).startswith("--set sweep.samples=0")
    code, printed, err = _cli(["run", toy, "--out", tmp_path / "o", "--set", "f.step=0.1", "--no-plots"], capsys)
    assert code == 0 and "components.f.step = 0.1" in printed, err
    assert len(pd.read_csv(tmp_path / "o" / "signals.csv")) == round(1.0 / 0.05) + 1     # the base step stays
