"""Fuzzed study files and measured logs give named errors only (hypothesis)."""
from __future__ import annotations

import math
import tempfile
from pathlib import Path

import numpy as np
import pandas as pd
import tomli_w
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from agrobot.measurements import CANONICAL, LogError, read_log
from agrobot.orchestrator.build import build_system
from agrobot.orchestrator.errors import InputError
from agrobot.orchestrator.resolver import resolve
from agrobot.orchestrator.study import Study

ROOT = Path(__file__).resolve().parent.parent
SETTINGS = settings(max_examples=60, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])

cells = st.one_of(st.floats(allow_nan=True, allow_infinity=True), st.integers(-10**6, 10**6),
                  st.sampled_from(["", "x", "1e3", "nan", "3 m"]))


@st.composite
def logs(draw):
    n = draw(st.integers(0, 40))
    columns = draw(st.lists(st.sampled_from(list(CANONICAL) + ["extra"]), min_size=0, max_size=9, unique=True))
    data = {c: draw(st.lists(cells, min_size=n, max_size=n)) for c in columns}
    if "t" in data and draw(st.booleans()):
        data["t"] = list(np.arange(n) * draw(st.sampled_from([0.01, 0.05, 50.0, -0.1, 0.0])))
    return pd.DataFrame(data)


@SETTINGS
@given(frame=logs(), fmt=st.sampled_from(["csv", "parquet"]))
def test_a_fuzzed_log_is_read_or_refused_by_name(frame, fmt):
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / f"log.{fmt}"
        try:
            if fmt == "csv":
                frame.to_csv(path, index=False)
            else:
                frame.astype(str).to_parquet(path) if len(frame.columns) else frame.to_parquet(path)
        except Exception:        # noqa: BLE001 - pandas cannot write it: nothing to test
            return
        try:
            out = read_log(path)
        except LogError as exc:
            assert str(path) in str(exc)
            return
        assert list(CANONICAL) == [c for c in out.columns if c in CANONICAL]
        assert np.all(np.isfinite(out[list(CANONICAL)].to_numpy(float)))


values = st.one_of(st.floats(allow_nan=True, allow_infinity=True), st.integers(-10**9, 10**9), st.booleans(),
                   st.text(max_size=8), st.lists(st.integers(0, 5), max_size=3))
FIELDS = ["name", "seed", "stop_time", "base_step", "start_time", "signals_format", "realtime", "analysis", "bogus"]
COMPONENTS = ["steering", "tractor", "gps", "mpc", "nosuch"]
PARAMS = ["kp", "speed", "model", "latency", "noise_std", "x"]


@SETTINGS
@given(study=st.dictionaries(st.sampled_from(FIELDS), values, max_size=4),
       params=st.dictionaries(st.tuples(st.sampled_from(COMPONENTS), st.sampled_from(PARAMS)), values, max_size=3),
       top=st.dictionaries(st.sampled_from(["sweep", "exports", "connections", "other"]),
                           st.one_of(values, st.dictionaries(st.text(max_size=4), values, max_size=2)), max_size=2))
def test_a_fuzzed_study_loads_or_is_refused_by_name(study, params, top):
    data: dict = {"extends": str(ROOT / "studies" / "figure8.toml"), "study": dict(study), **top}
    comps: dict = {}
    for (comp, key), value in params.items():
        comps.setdefault(comp, {"parameters": {}})["parameters"][key] = value
    if comps:
        data["components"] = comps
    clean = _toml_safe(data)
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "fuzz.toml"
        try:
            path.write_text(tomli_w.dumps(clean))
        except (TypeError, ValueError):
            return
        try:
            loaded = Study.load(path)
            build_system(resolve(loaded.with_values({"study.stop_time": 0.2}) if loaded.sweep is None else loaded))
        except InputError as exc:
            assert "fuzz.toml" in str(exc) or "--" in str(exc) or "override" in str(exc), str(exc)


def _toml_safe(x):
    """TOML has no NaN-free guarantee for nested None; drop None and keep the rest."""
    if isinstance(x, dict):
        return {str(k): _toml_safe(v) for k, v in x.items() if v is not None}
    if isinstance(x, list):
        return [_toml_safe(v) for v in x if v is not None]
    if isinstance(x, float) and math.isnan(x):
        return x
    return x
