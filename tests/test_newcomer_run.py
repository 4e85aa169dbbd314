"""What a newcomer meets on a first run through the shipped studies and the docs: no note about an
input the study's author left open on purpose, counts printed with their noun's number, a sweep too
short for its own bounds refused before its first point, a saved fields result loaded with its track."""
from __future__ import annotations

import math
import re
import types

import numpy as np
import pytest

from agrobot.components.models.figure8_path import Figure8Path
from agrobot.orchestrator.build import build_system
from agrobot.orchestrator.errors import InputError
from agrobot.orchestrator.mcap_out import LiveView
from agrobot.orchestrator.resolver import resolve
from agrobot.orchestrator.study import Study
from agrobot.studies import shipped
from tests.commands import cli

STUDIES = sorted(p.name for p in shipped().glob("*.toml"))


@pytest.mark.parametrize("name", STUDIES)
def test_a_shipped_study_says_no_held_input_note(name):
    """Every input a shipped study leaves open is named in its [study] allow_unconnected (its
    author's choice, recorded in run.json): a newcomer's run prints no 'is unconnected' note."""
    system = build_system(resolve(Study.load(shipped(name))))
    assert system.held_lines() == []


def test_the_live_view_counts_with_the_noun_in_its_number(tmp_path):
    """One viewer is '1 viewer', one instant '1 instant', one message '1 message'; none or two take the plural."""
    one = types.SimpleNamespace(sent=1, url="ws://127.0.0.1:1", max_viewers=1,
                                viewers={"foxglove.sdk.v1": 1, "dropped": 1, "closed_slow": 1})
    said = LiveView.report.fget(one)
    assert said.startswith("1 instant sent to ws://127.0.0.1:1; 1 viewer (1 foxglove.sdk.v1)"), said
    assert "1 message dropped" in said and "1 viewer closed" in said and "viewers" not in said.split("(")[0]
    two = types.SimpleNamespace(sent=2, url="u", max_viewers=2, viewers={})
    assert LiveView.report.fget(two) == "2 instants sent to u; 0 viewers"
    # the line the run prints as it starts serving, with --live-viewers 1
    done = cli("run", shipped("figure8.toml"), "--out", tmp_path / "run", "--no-plots", "--live", "127.0.0.1:0",
               "--live-viewers", "1", "--set", "study.stop_time=20", timeout=120)
    assert done.returncode == 0, done.stderr
    assert "to at most 1 viewer (" in done.stdout and "1 viewers" not in done.stdout, done.stdout


def test_a_sweep_too_short_for_a_bound_says_so_before_any_point_and_counts_it_not_judged(tmp_path):
    """A figure-8 sweep cut to 30 s: its nominal run (2 m/s, 8 s ramp, then 5 s settling) reaches no
    straight before it ends, so euclid_max_straight has no value there. Said before the first point
    runs (the file, study.stop_time, the stop time that reaches a straight), and the point without
    the figure counted as not judged, not as within (it was 100 % within before)."""
    study = tmp_path / "short.toml"
    study.write_text(f'extends = "{shipped("figure8.toml").as_posix()}"\n[study]\nstop_time = 30.0\n'
                     '[sweep]\n[sweep.parameters]\n"reference.speed" = [1.0, 2.0]\n')
    done = cli("sweep", study, "--out", tmp_path / "out", "--engine", "python", "--workers", "1",
               "--no-progress", "--no-plots", timeout=300)
    assert done.returncode == 0, done.stderr
    warning = next(line for line in done.stderr.splitlines() if line.startswith("warning: "))
    assert f"{study}: study.stop_time = 30 s is too short for the bound on euclid_max_straight" in warning
    assert done.stderr.index(warning) < done.stderr.index("sweep: 2 points on 1 worker")   # before any point
    # the reference (ramp T = 8 s: s = v (t - T/2) past it) is settled at T + 5 s = 13 s; the first
    # straight after that starts where the path's own segment label turns 0 (Figure8Path)
    path, v, ramp = Figure8Path(10.0, 20.0), 2.0, 8.0
    s = next(s for s in np.arange(v * (13.0 - ramp / 2), 1000.0, 0.01) if path.pose(s)[4] == 0)
    need = math.ceil(ramp / 2 + s / v + 1.0)
    assert warning.endswith(f"run at least {need} s: --set study.stop_time={need}"), warning
    row = next(line for line in done.stdout.splitlines() if line.startswith("euclid_max_straight "))
    assert row.endswith(f"1 of 1 judged (100%); 1 not judged: run at least {need} s"), row


def test_a_sweep_under_engine_auto_finds_the_c_cores_once_and_runs_its_points_with_the_choice(tmp_path, monkeypatch):
    """The engine is chosen on the first point's system: its C cores found once (not again to
    choose), and the nominal run and the points given the engine chosen, not 'auto' again."""
    from agrobot.orchestrator import sweep as sweep_module
    from agrobot.orchestrator.compiled import simulation

    found = []

    def counted(system):
        found.append(system)
        return simulation_cores_of(system)

    simulation_cores_of = simulation.cores_of
    monkeypatch.setattr(simulation, "cores_of", counted)
    monkeypatch.setattr(sweep_module, "cores_of", counted)
    study = Study.load(shipped("speed_sweep.toml"), ["study.stop_time=40"])
    runner = sweep_module.SweepRun(study, tmp_path / "out", engine="auto")
    runner.validate()
    assert len(found) == 1
    assert runner.ran in ("compiled", "python")
    engines = []
    monkeypatch.setattr(sweep_module, "simulate_point", lambda study, folder, engine, keep_signals: (
        engines.append(engine) or {"status": "completed", "metrics": {}}))
    runner.run_nominal()
    assert engines and set(engines) == {runner.ran}


def test_convert_checks_its_output_with_the_shared_file_check(tmp_path, monkeypatch):
    """convert(out=...) refuses a file as every other saved result does (results.check_file), before reading."""
    import agrobot
    from agrobot import api

    asked = []
    monkeypatch.setattr(api, "check_file", lambda *a, **k: asked.append(a) or (_ for _ in ()).throw(
        InputError("refused")))
    with pytest.raises(InputError, match="refused"):
        agrobot.convert(tmp_path / "nothing.nmea", out=tmp_path / "log.csv")
    assert asked and asked[0][0] == tmp_path / "log.csv" and set(asked[0][1]) == {".csv", ".parquet"}


def test_a_field_from_a_track_loads_back_with_its_track_line(tmp_path):
    """Four 100 m passes 6 m apart (tests.test_two_doors._track): the saved result, loaded back,
    still says it was made from a track of 4 straight passes."""
    import agrobot
    import agrobot.api
    from tests.test_two_doors import _track

    track = _track(tmp_path)
    made = agrobot.api.fields(track, from_track=True, width=6.0, signals=["lat=track.lat[deg]", "lon=track.lon[deg]"],
                          time="t[s]", out=tmp_path / "field", plots=False)
    back = agrobot.load_result(tmp_path / "field")
    assert isinstance(back, agrobot.FieldsResult) and "4 straight passes" in made.track
    assert back.track == made.track


def _written_by_pages() -> dict[str, list[tuple[str, bool]]]:
    """--out folder or file -> [(page, with --overwrite)] of every command the README and the docs
    print (continuation lines joined; placeholders such as OUT, DIR, X.fmu, YOUR_STUDY left out)."""
    root = shipped().parents[2]
    command = re.compile(r"(?:python3? -m agrobot|^\$? ?agrobot|`agrobot) [a-z-]+ [^`\n]*?--out (\S+?)(?=[\s`]|$)([^`\n]*)",
                         re.M)
    written: dict[str, list[tuple[str, bool]]] = {}
    for page in [root / "README.md", *sorted((root / "docs").glob("*.md"))]:
        text = page.read_text(encoding="utf-8").replace("\\\n", " ")
        for m in command.finditer(text):
            out = m.group(1)
            if re.fullmatch(r"[A-Z_]+(\.\w+)?|X\.\w+", out) or "YOUR" in out or "MY_" in out:
                continue
            written.setdefault(out, []).append((page.name, "--overwrite" in m.group(0)))
    return written


def test_each_page_of_the_docs_writes_its_own_folders():
    """A newcomer following the README, then the pages, never meets 'pass --overwrite': no --out of
    one page is another's, and a page that writes one twice says --overwrite the second time."""
    written = _written_by_pages()
    assert "results/figure8" in written and len(written) > 20              # the commands were found
    shared = {out: pages for out, pages in written.items() if len({p for p, _ in pages}) > 1}
    assert shared == {}
    again = {out: pages for out, pages in written.items() if len(pages) > 1 and not all(o for _, o in pages[1:])}
    assert again == {}


def test_a_figure8_run_ended_during_the_ramp_says_so_not_a_length_that_moves_with_it(tmp_path):
    """Stopped at 6 s (the 8 s ramp not finished), the run says the speed still rises and names
    the ramp; before, it asked for 11 s at 6 s and for 13 s at 8 s."""
    done = cli("run", shipped("figure8.toml"), "--out", tmp_path / "r", "--no-plots", "--engine", "python",
               "--set", "study.stop_time=6", timeout=120)
    assert done.returncode == 1 and "Traceback" not in done.stderr, done.stderr
    assert "the speed still rises at its end (t = 6 s)" in done.stderr and "reference.ramp_time" in done.stderr
    assert "must last beyond" not in done.stderr
