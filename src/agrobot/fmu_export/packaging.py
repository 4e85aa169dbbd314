"""Build and package an FMI 2.0 or 3.0 FMU from a folder holding ``modelDescription.xml`` and
``sources/``: the FMI headers (from fmpy) are added to the sources, the binary for this platform
is built with fmpy.build (CMake + the C compiler, hidden visibility: only the functions the FMI
headers mark for export leave the binary), and the archive made in memory: what writes it is the
result's ``save`` (agrobot.results.ExportedFile: the one output rule, written aside and renamed)."""
from __future__ import annotations

import contextlib
import io
import os
import shutil
import sys
import tempfile
import zipfile
from pathlib import Path

import fmpy
from fmpy.build import build_platform_binary

FMI_HEADERS = {2: ("fmi2Functions.h", "fmi2FunctionTypes.h", "fmi2TypesPlatform.h"),
               3: ("fmi3Functions.h", "fmi3FunctionTypes.h", "fmi3PlatformTypes.h")}


# fmpy's copy of fmi2Functions.h always exports and never prefixes; the standard's header prefixes
# every function with FMI2_FUNCTION_PREFIX when it is defined (a source-code FMU linked beside
# others) and then leaves the export to the linker. These lines restore that behaviour.
_FMI2_STANDARD_NAMING = """
#if !defined(FMI2_Export)
  #if defined(FMI2_FUNCTION_PREFIX)
    #define FMI2_Export
  #elif defined _WIN32 || defined __CYGWIN__
    #define FMI2_Export __declspec(dllexport)
  #elif __GNUC__ >= 4
    #define FMI2_Export __attribute__ ((visibility ("default")))
  #else
    #define FMI2_Export
  #endif
#endif
#if defined(FMI2_FUNCTION_PREFIX)
  #define fmi2Paste(a, b) a ## b
  #define fmi2PasteB(a, b) fmi2Paste(a, b)
  #define fmi2FullName(name) fmi2PasteB(FMI2_FUNCTION_PREFIX, name)
#else
  #define fmi2FullName(name) name
#endif
"""


def _fmi2_header(text: str) -> str:
    """fmpy's fmi2Functions.h with the standard's export and prefix macros."""
    start = text.index("#if defined _WIN32 || defined __CYGWIN__")
    end = text.index("#define fmi2FullName(name) name") + len("#define fmi2FullName(name) name")
    return text[:start] + _FMI2_STANDARD_NAMING.strip() + text[end:]


class PackagingError(Exception):
    """The FMU could not be built (the message carries the end of the build log)."""


@contextlib.contextmanager
def _output_to(path: Path):
    """Send this process's stdout and stderr (file descriptors: subprocesses too) to a file."""
    sys.stdout.flush()
    sys.stderr.flush()
    saved = os.dup(1), os.dup(2)
    with open(path, "wb") as f:
        os.dup2(f.fileno(), 1)
        os.dup2(f.fileno(), 2)
        try:
            yield
        finally:
            os.dup2(saved[0], 1)
            os.dup2(saved[1], 2)
            os.close(saved[0])
            os.close(saved[1])


def archive(entries: dict[str, Path | str | bytes]) -> bytes:
    """The zip archive of ``entries`` (a member name -> a file, text or bytes), made in memory."""
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w", zipfile.ZIP_DEFLATED) as zf:
        for name, content in entries.items():
            if isinstance(content, Path):
                zf.write(content, name)
            else:
                zf.writestr(name, content)
    return buffer.getvalue()


def package_fmu(source_root: Path, fmi_version: int = 2, name: str = "model.fmu") -> bytes:
    """The FMU of ``source_root`` (modelDescription.xml, sources/) with the binary for this
    platform, as the archive's bytes; ``name`` for the messages."""
    fmpy_c = Path(fmpy.__file__).with_name("c-code")
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp) / "fmu"
        shutil.copytree(source_root, root)
        for header in FMI_HEADERS[fmi_version]:
            if not (root / "sources" / header).exists():
                text = (fmpy_c / header).read_text()
                (root / "sources" / header).write_text(_fmi2_header(text) if header == "fmi2Functions.h" else text)
        build, log = Path(tmp) / "build", Path(tmp) / "build.log"
        build.mkdir()
        try:
            with _output_to(log):
                build_platform_binary(root, build, cmake_options={
                    "CMAKE_C_STANDARD_LIBRARIES:STRING": "-lm", "CMAKE_C_FLAGS:STRING": "-O2 -fvisibility=hidden"})
        except Exception as exc:
            tail = log.read_text(errors="replace")[-2000:] if log.exists() else ""
            raise PackagingError(f"building {name} failed (needs cmake and a C compiler): {exc}\n{tail}") from None
        return archive({path.relative_to(root).as_posix(): path for path in sorted(root.rglob("*")) if path.is_file()})
