"""A study that extends a file which is not there names the path as read: relative to the extending
file's own folder, not to where the command runs."""
from __future__ import annotations

import pytest

from agrobot.orchestrator.study_files import StudyError, read_study_file


def test_a_missing_parent_names_the_folder_it_is_read_from(tmp_path):
    mine = tmp_path / "mine" / "my_tractor.toml"
    mine.parent.mkdir()
    mine.write_text('extends = "figure8.toml"\n')
    with pytest.raises(StudyError) as err:
        read_study_file(mine)
    text = str(err.value)
    assert "field extends: 'figure8.toml' is not a file" in text
    assert str(mine.parent.resolve()) in text and str(mine.parent.resolve() / "figure8.toml") in text
