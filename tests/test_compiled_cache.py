"""The compiled engine's cache is trusted only when it is ours (orchestrator.compiled.toolchain): a
folder another user owns or others may write is refused by name, a library is loaded only when its
bytes hash to what was built (a planted library's constructor never runs), and a truncated library
is built again."""
from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from agrobot.orchestrator.compiled import toolchain

pytestmark = pytest.mark.skipif(shutil.which("cc") is None and shutil.which("gcc") is None, reason="no C compiler")

LOOP = """int agc_run(double *p, double *y, double *u, long n, double *out) { return (int)n + 1; }
"""
PLANTED = """#include <stdio.h>
__attribute__((constructor)) static void planted(void) { FILE *f = fopen("%s", "w"); if (f) fclose(f); }
const char *agc_token(void) { return "%s"; }
int agc_run(double *p, double *y, double *u, long n, double *out) { return -1; }
"""


@pytest.fixture
def cache(tmp_path, monkeypatch):
    monkeypatch.setenv("AGROBOT_CACHE", str(tmp_path / "cache"))
    monkeypatch.setattr(toolchain, "_LOADED", {})
    return tmp_path / "cache" / "compiled"


def _load(units=None):
    toolchain._LOADED.clear()
    return toolchain.library(units or {"loop.c": LOOP}, [], [])


BUILD = f"""
from agrobot.orchestrator.compiled import toolchain
print(toolchain.library({{"loop.c": {LOOP!r}}}, [], [])[1])
"""


def _built_by_another_process() -> str:
    """The shape's key, its library built and loaded by another process (a library this process has
    loaded stays mapped under its path: what is tested is what a later process finds in the cache)."""
    done = subprocess.run([sys.executable, "-c", BUILD], capture_output=True, text=True, timeout=120, check=True)
    return done.stdout.split()[-1]


def test_a_planted_library_never_runs_and_is_replaced_by_a_build(cache, tmp_path):
    key = _built_by_another_process()
    marker = tmp_path / "constructor-ran"
    source = tmp_path / "planted.c"
    source.write_text(PLANTED % (marker, key))          # even the right token: its bytes are not what was built
    planted = cache / key / "libloop.so"
    subprocess.run([toolchain.compiler(), "-shared", "-fPIC", "-o", str(planted), str(source)], check=True)
    lib, _, built = _load()
    assert not marker.exists(), "the planted library's constructor ran"
    assert built and lib.agc_run(None, None, None, 1, None) == 2


def test_a_truncated_library_is_built_again(cache):
    key = _built_by_another_process()
    path = cache / key / "libloop.so"
    path.write_bytes(path.read_bytes()[:100])
    lib, _, built = _load()
    assert built and lib.agc_run(None, None, None, 6, None) == 7
    _, _, built = _load()                               # and then it is trusted as built
    assert not built


def test_a_cache_others_may_write_is_refused_by_name(cache):
    _load()
    os.chmod(cache, 0o777)
    with pytest.raises(toolchain.UntrustedCache) as refused:
        _load()
    assert str(cache) in str(refused.value) and "writable by others" in str(refused.value)
    os.chmod(cache, 0o700)
    assert _load()[0] is not None


@pytest.mark.skipif(os.getuid() != 0, reason="giving a folder to another user needs root")
def test_a_cache_of_another_user_is_refused_by_name(cache):
    _load()
    os.chown(cache, 4242, -1)
    with pytest.raises(toolchain.UntrustedCache) as refused:
        _load()
    assert str(cache) in str(refused.value) and "owned by user 4242" in str(refused.value)


def test_a_new_cache_is_private(cache):
    _load()
    assert cache.stat().st_mode & 0o077 == 0
    assert Path(cache).is_dir()


@pytest.mark.parametrize("damaged", [False, True])
def test_processes_compiling_one_shape_at_once_all_load_a_whole_library(cache, damaged):
    """Four processes (pytest-xdist workers, sweep workers) building the same shape at once, in an
    empty cache or over a damaged library: every one loads a library that runs, and the cache holds
    that shape's folder alone (each build written aside under its own name and moved into place;
    a damaged folder renamed aside before it is removed)."""
    if damaged:
        key = _built_by_another_process()
        (cache / key / "libloop.so").write_bytes(b"\x7fELF damaged")
    procs = [subprocess.Popen([sys.executable, "-c", BUILD + "print(toolchain.library({'loop.c': "
                               f"{LOOP!r}}}, [], [])[0].agc_run(None, None, None, 2, None))"],
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True) for _ in range(4)]
    outputs = [p.communicate(timeout=120) for p in procs]
    assert all(p.returncode == 0 for p in procs), [err for _, err in outputs]
    keys = {out.split()[0] for out, _ in outputs}
    assert len(keys) == 1 and all(out.split()[1] == "3" for out, _ in outputs)
    assert [p.name for p in cache.iterdir()] == [keys.pop()]
    lib, _, built = _load()
    assert not built and lib.agc_run(None, None, None, 4, None) == 5
