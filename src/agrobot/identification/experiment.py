"""Identification experiments: simulated through the orchestrator from a study file, or read from
a measured log in the canonical format (t, delta_cmd, delta, v, yaw_rate, ...)."""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd
from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator

from agrobot.measurements import LogError, load_log
from agrobot.measurements.audit import require_causal
from agrobot.measurements.log import speed_estimate
from agrobot.orchestrator.runner import simulate
from agrobot.orchestrator.study import Study, StudyError
from agrobot.orchestrator.units import UnitError, to_si

from .fitting import STRUCTURES
from .multisine import MultisineDesign, realisation

NEEDED = ("t", "delta_cmd", "delta", "v", "yaw_rate")      # columns of the canonical log it reads
# what each need is for (a partial log is refused naming them)
WHY = {"delta_cmd": "the multisine on the steering command is the reference (the instrument of the FRF)",
       "delta": "the measured wheel angle is the FRF's input", "yaw_rate": "the gyro's yaw rate is the FRF's output"}


class IdentificationConfig(BaseModel):
    model_config = ConfigDict(extra="forbid")
    speeds: list[float] = Field(default=[2.0], min_length=1)
    speed_input: str = "tractor.speed"
    excitation: str = "excitation"
    signals: dict[str, str]
    sample_rate: float = Field(20.0, gt=0)
    period: float = Field(50.0, gt=0)
    periods: int = Field(4, ge=2)
    transient_periods: int = Field(1, ge=0)
    realisations: int = Field(4, ge=1)
    band: tuple[float, float] = (0.02, 2.0)
    kind: str = "odd_odd"
    rms: float | str = "4 deg"
    validation_bands: list[tuple[float, float]] = [(0.0, 2.0), (0.0, 8.0)]
    validation_periods: int = Field(2, ge=1)
    detection_band: tuple[float, float] | None = (0.02, 8.0)   # wide odd-odd run for the NL analysis
    detection_realisations: int = Field(2, ge=1)
    models: list[str] = list(STRUCTURES)
    delay: bool = False

    @field_validator("models")
    @classmethod
    def _models(cls, v: list[str]) -> list[str]:
        bad = [m for m in v if m not in STRUCTURES]
        if bad:
            raise ValueError(f"unknown model structures {bad}; expected some of {list(STRUCTURES)}")
        return v

    @field_validator("signals")
    @classmethod
    def _signals(cls, v: dict[str, str]) -> dict[str, str]:
        missing = [k for k in ("delta_cmd", "delta", "yaw_rate") if k not in v]
        if missing:
            raise ValueError(f"missing signal mappings {missing}")
        return v

    @property
    def period_samples(self) -> int:
        return int(round(self.period * self.sample_rate))

    @property
    def rms_rad(self) -> float:
        return float(to_si(self.rms, "rad"))


@dataclass
class Experiment:
    """Steady-state data of one experiment, shaped (realisations, periods, samples)."""

    fs: float
    excited: np.ndarray
    r: np.ndarray
    u: np.ndarray
    y: np.ndarray
    speed: float
    notes: list[str] = field(default_factory=list)
    full: list[pd.DataFrame] = field(default_factory=list)   # each realisation's whole record
    transient_samples: int = 0

    @property
    def period_samples(self) -> int:
        return self.u.shape[-1]


def config_of(study: Study) -> IdentificationConfig:
    section = study.section("identification")
    if section is None:
        raise StudyError(f"{study.path}: no [identification] section")
    try:
        cfg = IdentificationConfig.model_validate(section)
        cfg.rms_rad
    except ValidationError as err:
        lines = [f"{study.path}: invalid [identification] section"]
        lines += [f"  field identification.{'.'.join(map(str, e['loc']))}: {e['msg']}" for e in err.errors()]
        raise StudyError("\n".join(lines)) from None
    except UnitError as exc:
        raise StudyError(f"{study.path}: field identification.rms: {exc}") from None
    if not math.isclose(cfg.period * cfg.sample_rate, cfg.period_samples):
        raise StudyError(f"{study.path}: identification.period x sample_rate must be a whole number of samples")
    return cfg


def _design(cfg: IdentificationConfig, band, kind: str) -> MultisineDesign:
    f0 = cfg.sample_rate / cfg.period_samples
    lo = max(band[0], f0)
    return MultisineDesign(cfg.sample_rate, cfg.period_samples, lo, band[1], cfg.rms_rad, kind)


def simulate_experiment(study: Study, cfg: IdentificationConfig, speed: float,
                        band, kind: str, realisations: int, periods: int, seed: int) -> Experiment:
    """Run ``realisations`` co-simulations of transient + ``periods`` periods of a fresh random-phase
    multisine each, at ``speed``; sample the signals at the identification rate."""
    design = _design(cfg, band, kind)
    rng = np.random.default_rng(seed)
    n_per = cfg.transient_periods + periods
    N = cfg.period_samples
    step = 1.0 / cfg.sample_rate
    comp, port = cfg.speed_input.split(".", 1)
    if cfg.excitation not in study.components or comp not in study.components:
        raise StudyError(f"{study.path}: identification.excitation / speed_input name unknown components")
    base = (study.without("sweep") if study.sweep else study).with_component(cfg.excitation, step=step)
    rs, us, ys, full = [], [], [], []
    for m in range(realisations):
        values = realisation(design, rng)
        run = base.with_values({"study.stop_time": study.study.start_time + n_per * cfg.period,
                                "study.seed": int(rng.integers(2**31)),
                                f"{cfg.excitation}.values": values.tolist(), f"{comp}.inputs.{port}": speed})
        rec, _ = simulate(run)
        frame = rec.to_frame()
        every = int(round(step / study.study.base_step))
        frame = frame.iloc[::every].reset_index(drop=True).iloc[: n_per * N]
        for key, column in cfg.signals.items():
            if column not in frame:
                raise StudyError(f"{study.path}: identification.signals.{key}: no signal {column!r}")
        log = pd.DataFrame({"t": frame["t"], **{k: frame[c] for k, c in cfg.signals.items()}})
        log["v"] = speed
        full.append(log)
        steady = slice(cfg.transient_periods * N, n_per * N)
        rs.append(log["delta_cmd"].to_numpy()[steady].reshape(periods, N))
        us.append(log["delta"].to_numpy()[steady].reshape(periods, N))
        ys.append(log["yaw_rate"].to_numpy()[steady].reshape(periods, N))
    return Experiment(cfg.sample_rate, design.excited, np.array(rs), np.array(us), np.array(ys), speed,
                      full=full, transient_samples=cfg.transient_periods * N)


# ---------------------------------------------------------------------------------------------
# measured logs

def read_log(path: Path, resample: bool = False, recording=None) -> tuple[pd.DataFrame, dict | None]:
    """(log with the columns identification needs, import report): a table or a raw field
    recording (measurements.load_log checks it; ``resample``: put a jittered clock on an even
    grid; ``recording``: ImportOptions for a raw recording)."""
    frame, report = load_log(path, ("t",), resample_jitter=resample, recording=recording)
    require_causal(frame, str(path))              # a response leading its input: refused, said why
    missing = [c for c in WHY if c not in frame]
    if missing:
        raise LogError(f"{path}: identification not possible (the yaw stage is not judged): "
                       + "; ".join(f"no {c} ({WHY[c]})" for c in missing)
                       + f"; the log has {', '.join(map(str, frame.columns))}")
    if "v" not in frame:                              # the receiver's speed, else the track's, with a note
        speed, source = speed_estimate(frame)
        if speed is not None:
            frame = frame.assign(v=speed)
            frame.attrs["speed_from"] = source
    return frame, report


def hold_factor(r: np.ndarray, tol: float) -> float:
    """How many log samples a command value is held for on average (1: it changes every sample;
    2.5: a 20 Hz command in a 50 Hz log)."""
    changes = int(np.sum(np.abs(np.diff(r)) > tol))
    return len(r) / (changes + 1) if changes >= 4 else 1.0


def detect_period(r: np.ndarray, min_samples: int = 8) -> int:
    """Smallest N with r[t] == r[t - N] (to 1e-6 of its range) over most of the samples where the
    command moves. A command
    held over m log samples (a 20 Hz command in a 100 Hz log) repeats itself at every lag below m:
    the search starts beyond m, in steps of m when m is whole."""
    scale = np.ptp(r) or 1.0
    hold = hold_factor(r, 1e-6 * scale)
    step = int(round(hold)) if abs(hold - round(hold)) < 0.05 else 1
    first = max(min_samples, int(math.ceil(hold)) + 1)
    moves = np.r_[False, np.abs(np.diff(r)) > 1e-6 * scale]

    def match(N: int) -> float:
        """The share of the samples where the command moves that repeat N samples later (a command
        held for seconds repeats itself at any short lag inside its holds: not a period)."""
        m = moves[N:]
        if m.sum() < 10:
            return 0.0
        return float(np.mean((np.abs(r[N:] - r[:-N]) <= 1e-6 * scale)[m]))

    for N in range(step * -(-first // step), len(r) // 2 + 1, step):
        if match(N) > 0.45:
            # a command held over a fractional number of samples also matches one lag early
            near = range(N, min(N + int(math.ceil(hold)) + 1, len(r) // 2 + 1))
            return max(near, key=match)
    raise LogError("no period found in delta_cmd: the excitation must be periodic (a multisine) "
                   "and the log must hold at least two periods")


def experiment_from_log(frame: pd.DataFrame, where: str, period_s: float | None = None,
                        speed: float | None = None, band: tuple[float, float] | None = None) -> Experiment:
    """Split a log into realisations (where the command stops repeating), drop each one's first
    period as transient, keep whole periods; detect what was not given and say so."""
    notes = []
    t = frame["t"].to_numpy()
    fs = 1.0 / float(np.median(np.diff(t)))
    r = frame["delta_cmd"].to_numpy()
    if period_s is None:
        N = detect_period(r)
        notes.append(f"period detected from delta_cmd: {N} samples = {N / fs:.6g} s (f0 = {fs / N:.6g} Hz)")
    else:
        N = int(round(period_s * fs))
    scale = np.ptp(r) or 1.0
    repeats = np.zeros(len(r), dtype=bool)
    repeats[N:] = np.abs(r[N:] - r[:-N]) <= 1e-6 * scale
    # a realisation: a stretch where samples repeat the previous period, plus that first period
    runs, start = [], None
    for i in range(N, len(r) + 1):
        on = i < len(r) and repeats[i]
        if on and start is None:
            start = i - N
        if not on and start is not None:
            runs.append((start, i))
            start = None
    blocks = []
    for a, b in runs:
        whole = (b - a) // N
        if whole >= 3:                        # one transient + at least two steady periods
            blocks.append((a, whole))
    if not blocks:
        raise LogError(f"{where}: too few periods: each realisation needs a transient period and at "
                       f"least 2 steady periods of {N} samples")
    P = min(w for _, w in blocks) - 1
    notes.append(f"{len(blocks)} realisation(s) found, {P} steady period(s) each used "
                 f"(first period of each dropped as transient)")
    def stack(col):
        x = frame[col].to_numpy()
        return np.array([x[a + N: a + N + P * N].reshape(P, N) for a, _ in blocks])
    R = np.fft.rfft(stack("delta_cmd").mean(axis=(0, 1)))
    mag = np.abs(R)
    excited = np.flatnonzero(mag > 1e-3 * mag.max())
    excited = excited[excited > 0]
    hold = hold_factor(r, 1e-6 * scale)
    if hold > 1.2:        # a held command's spectral images above its own Nyquist frequency are not excitation
        excited = excited[excited * fs / N < fs / (2 * hold)]
        notes.append(f"delta_cmd is held over {hold} log samples (a {fs / hold:.4g} Hz command in a {fs:.4g} Hz log): "
                     f"lines above {fs / (2 * hold):.4g} Hz are its images, not excitation")
    if band is not None:
        excited = excited[(excited * fs / N >= band[0]) & (excited * fs / N <= band[1])]
    if len(excited) == 0:
        raise LogError(f"{where}: no excited line in the steering command's period-average "
                       f"(period {N / fs:.4g} s{', band ' + str(band) + ' Hz' if band is not None else ''}): "
                       f"identification needs a periodic multisine on delta_cmd; give --period or --band, or "
                       f"use `diagnose` for a log of ordinary driving")
    notes.append(f"excited lines detected: {len(excited)} from {excited[0] * fs / N:.4g} to "
                 f"{excited[-1] * fs / N:.4g} Hz" + (" (odd-odd)" if np.all(excited % 4 == 1) else
                                                     " (odd)" if np.all(excited % 2 == 1) else ""))
    if speed is None and "v" not in frame:
        raise LogError(f"{where}: no speed in the log (no v, gnss_speed or x, y): give it with --speed")
    if speed is None:
        speed = float(np.median(frame["v"]))
        notes.append(f"speed from column v: median {speed:.3f} m/s")
    full = [frame.iloc[a: a + w * N].reset_index(drop=True) for a, w in blocks]
    return Experiment(fs, excited, stack("delta_cmd"), stack("delta"), stack("yaw_rate"), speed, notes,
                      full=full, transient_samples=N)


def experiment_to_log(experiments: list[Experiment]) -> pd.DataFrame:
    """The canonical log of simulated experiments (realisations one after the other)."""
    parts, t0 = [], 0.0
    for exp in experiments:
        for log in exp.full:
            part = log.copy()
            part["t"] = part["t"] - part["t"].iloc[0] + t0
            t0 = part["t"].iloc[-1] + 1.0 / exp.fs
            parts.append(part)
    return pd.concat(parts, ignore_index=True)
