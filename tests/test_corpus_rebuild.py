"""The corpus is rebuilt from git mirrors as the manifest's sources say, byte for byte, and the
tricycle's speed is derived from its encoder as its derive script states.

Run as programs (tests and benchmarks import nothing of each other) on generated data only: a git
repository made here with known files and two commits, a manifest naming it, and tricycle rows whose
encoder counts a known front-wheel speed through the 32-bit counter's wrap."""
from __future__ import annotations

import math
import subprocess
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
REBUILD = ROOT / "benchmarks" / "corpus_rebuild.py"
DERIVE = ROOT / "benchmarks" / "tricycle_derive_speed.py"
REPO = "someone/recordings"


def git(cwd: Path, *args: str) -> str:
    return subprocess.run(["git", "-c", "user.name=t", "-c", "user.email=t@example.org", *args], cwd=cwd,
                          capture_output=True, text=True, check=True).stdout.strip()


def upstream(tmp: Path) -> tuple[Path, str, str]:
    """A mirror (bare clone) of a repository with two commits: (mirrors folder, first, second)."""
    work = tmp / "work"
    (work / "data" / "run" / "raw").mkdir(parents=True)
    (work / "data" / "log.bin").write_bytes(bytes(range(256)) * 3)
    (work / "data" / "run" / "t").write_bytes(b"\x00\x01\r\n\x02")
    (work / "data" / "run" / "raw" / "big").write_text("left out")
    (work / "README.md").write_text("upstream readme\n")
    git(work, "init", "-q")
    git(work, "add", ".")
    git(work, "commit", "-q", "-m", "first")
    first = git(work, "rev-parse", "HEAD")
    (work / "data" / "log.bin").write_bytes(b"changed later")
    git(work, "commit", "-q", "-am", "second")
    mirrors = tmp / "mirrors"
    git(tmp, "clone", "-q", "--bare", str(work), str(mirrors / REPO.replace("/", "+") / "repo"))
    return mirrors, first, git(work, "rev-parse", "HEAD")


def manifest(tmp: Path, commit: str, origin_commit: str | None = None) -> Path:
    path = tmp / "manifest.toml"
    path.write_text(f'''[[recording]]
name = "generated"
root = "corpus"
path = "generated_dir/log.bin"
origin = "github {REPO} @ {origin_commit or commit}, data/log.bin"
[recording.source]
repo = "{REPO}"
commit = "{commit}"
leave_out = ["channels/raw/"]
[recording.source.files]
"log.bin" = "data/log.bin"
"channels/" = "data/run/"
"README.upstream.md" = "README.md"
''')
    return path


def rebuild(man: Path, corpus: Path, mirrors: Path) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, str(REBUILD), "--manifest", str(man), "--corpus", str(corpus),
                           "--mirrors", str(mirrors)], capture_output=True, text=True, timeout=120)


def test_the_files_come_out_byte_for_byte_at_the_named_commit(tmp_path):
    mirrors, first, _ = upstream(tmp_path)
    done = rebuild(manifest(tmp_path, first), tmp_path / "corpus", mirrors)
    assert done.returncode == 0, done.stderr
    out = tmp_path / "corpus" / "generated_dir"
    assert (out / "log.bin").read_bytes() == bytes(range(256)) * 3        # the first commit's, not the second's
    assert (out / "channels" / "t").read_bytes() == b"\x00\x01\r\n\x02"
    assert not (out / "channels" / "raw").exists()
    assert (out / "README.upstream.md").read_text() == "upstream readme\n"
    record = (tmp_path / "corpus" / "REBUILT.tsv").read_text().splitlines()
    assert len(record) == 4 and all(first in line for line in record[1:])


def test_a_missing_mirror_is_named_as_the_fetch_source_it_needs(tmp_path):
    mirrors, first, _ = upstream(tmp_path)
    done = rebuild(manifest(tmp_path, first), tmp_path / "corpus", tmp_path / "elsewhere")
    assert done.returncode == 2 and f"github:{REPO}" in done.stdout
    assert not (tmp_path / "corpus").exists()


def test_a_source_that_is_not_the_origin_is_refused(tmp_path):
    mirrors, first, second = upstream(tmp_path)
    done = rebuild(manifest(tmp_path, first, origin_commit=second), tmp_path / "corpus", mirrors)
    assert done.returncode == 1 and "'generated'" in done.stderr and "origin" in done.stderr


def test_a_commit_the_mirror_lacks_gives_the_newest_holding_the_file_and_says_so(tmp_path):
    mirrors, _, second = upstream(tmp_path)
    absent = "0123456789abcdef0123456789abcdef01234567"
    done = rebuild(manifest(tmp_path, absent), tmp_path / "corpus", mirrors)
    assert done.returncode == 0, done.stderr
    assert f"commit {absent} absent" in done.stdout and second in done.stdout
    assert (tmp_path / "corpus" / "generated_dir" / "log.bin").read_bytes() == b"changed later"
    assert second in (tmp_path / "corpus" / "REBUILT.tsv").read_text()


def test_the_tricycle_speed_is_the_encoder_difference_through_the_counter_wrap(tmp_path):
    """v_front = d(enc)/dt 2 pi R / ticks, v = v_front cos(delta), with the counter passing 2^32."""
    radius, ticks = 0.125, 35136
    (tmp_path / "dataset.txt").write_text(f"front_wheel_radius_meters = {radius}\nticks_per_rev = {ticks}\n")
    rng = np.random.default_rng(3)
    t = np.cumsum(np.r_[0.0, 1 / 30 + 0.002 * rng.standard_normal(599)])
    speed = 1.0 + 0.5 * np.sin(0.4 * t)                                     # m/s, the front wheel's
    count = np.r_[0.0, np.cumsum(speed[1:] * np.diff(t))] * ticks / (2 * math.pi * radius)
    enc = (np.round(count) + 2 ** 32 - 20000) % 2 ** 32                     # wraps after about 0.7 m
    delta, gyro = 0.8 * np.sin(0.3 * t), 0.01 * rng.standard_normal(len(t))
    rows = "\n".join(f"{a:.6f}, {int(b)}, {c:.6f}, {d:.6f}" for a, b, c, d in zip(t, enc, gyro, delta))
    (tmp_path / "dataset1.csv").write_text("#time, encoder, angular velocity, steering angle\n" + rows + "\n")
    done = subprocess.run([sys.executable, str(DERIVE), str(tmp_path)], capture_output=True, text=True, timeout=60)
    assert done.returncode == 0, done.stderr
    out = np.genfromtxt(tmp_path / "derived" / "dataset1_log.csv", delimiter=",", names=True)
    assert out.dtype.names == ("t", "delta", "v", "yaw_rate", "v_front")
    assert np.any(np.diff(enc) < 0)                                          # the counter did wrap
    quantum = 2 * math.pi * radius / ticks / np.diff(t).min()               # one tick over the shortest step
    assert np.max(np.abs(out["v_front"][1:] - speed[1:])) < quantum
    assert np.allclose(out["v"], out["v_front"] * np.cos(delta), atol=1e-8)
    assert out["v_front"][0] == out["v_front"][1]
    assert np.allclose(out["yaw_rate"], gyro, atol=1e-6) and np.allclose(out["delta"], delta, atol=1e-6)
