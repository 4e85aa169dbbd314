"""A file a run writes outside ``--out`` (an output parameter, e.g. ``--record``'s recordings) follows one
rule whether the run has an ``--out`` or not (orchestrator.output.write_aside): locked while written (a
second writer is refused), under a temporary name beside it, renamed over it when the run ends, all removed
and the file named on a full disk. Truth: the lines the test itself writes, the lock's refusal message."""
from __future__ import annotations

import errno
from pathlib import Path

import pytest

from agrobot.orchestrator.output import OutputError, OutputLock, write_aside
from agrobot.orchestrator.study import Study

STUDY = """[study]
name = "aside"
stop_time = 1.0
base_step = 0.1
seed = 1
[components.r]
type = "tests.test_command_rules:Recorder"
"""


def _placed(tmp_path: Path, target: Path):
    path = tmp_path / "s.toml"
    path.write_text(STUDY)
    study = Study.load(path, [f"r.record_file={target}"])
    placed, aside = write_aside(study, False, [path])
    return Path(placed.components["r"].parameters["record_file"]), aside


def test_a_file_written_aside_is_locked_and_renamed_over_its_target_when_the_run_ends(tmp_path):
    target = tmp_path / "rec" / "lines.txt"
    tmp, aside = _placed(tmp_path, target)
    assert tmp.parent == target.parent and tmp.name.startswith(".lines.txt.") and not target.exists()
    with pytest.raises(OutputError, match="another run or command .* is writing to it"):
        OutputLock(target).acquire()
    with aside.kept():
        tmp.write_text("1\n2\n")
    assert target.read_text() == "1\n2\n" and sorted(p.name for p in target.parent.iterdir()) == ["lines.txt"]
    OutputLock(target).acquire().release()            # let go when the run ended


def test_a_full_disk_while_writing_aside_removes_every_file_and_names_the_one_it_filled(tmp_path):
    target = tmp_path / "lines.txt"
    tmp, aside = _placed(tmp_path, target)
    with pytest.raises(OutputError) as refused:
        with aside.kept():
            tmp.write_text("1\n")
            raise OSError(errno.ENOSPC, "No space left on device", str(tmp))
    text = str(refused.value)
    assert f"{target}: the disk is full" in text and ".writing" not in text, text
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.toml"]
    OutputLock(target).acquire().release()
