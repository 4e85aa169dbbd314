"""A C library built on first use beside a Python reference that computes the same: ``choose`` picks
``c`` or ``python`` for an asked kernel (``auto``: C where the library builds, else Python, said once
per process on stderr with why; ``c``: the library or the reason it cannot be built, raised).
"""
from __future__ import annotations

import ctypes
import sys
from typing import Callable

from ..errors import InputError
from .toolchain import CompileError, CompilerMissing

KERNELS = ("auto", "c", "python")


class OptionalLibrary:
    """``load()`` builds and binds the library (toolchain.library); ``slower`` says what runs in
    Python instead and at what cost, for the one note."""

    def __init__(self, load: Callable[[], ctypes.CDLL], slower: str) -> None:
        self.load, self.slower = load, slower
        self.state: dict[str, object] = {}

    def choose(self, kernel: str) -> str:
        if kernel not in KERNELS:
            raise InputError(f"kernel {kernel!r}: expected one of {', '.join(KERNELS)}")
        if kernel == "python":
            return "python"
        if "lib" not in self.state and "missing" not in self.state:
            try:
                self.state["lib"] = self.load()
            except (CompilerMissing, CompileError, OSError) as exc:      # OSError: the cache folder not writable
                self.state["missing"] = exc
        if "lib" in self.state:
            return "c"
        if kernel == "c":
            raise self.state["missing"]         # type: ignore[misc]
        if not self.state.get("said"):
            why = self.state["missing"]
            why = "no C compiler was found ($CC, cc, gcc; the Debian package gcc installs one)" \
                if isinstance(why, CompilerMissing) else f"its C kernel could not be built: {why}"
            print(f"note: {self.slower}: {why}", file=sys.stderr)
            self.state["said"] = True
        return "python"

    def lib(self) -> ctypes.CDLL:
        """The library, built now if not yet (a caller that chose ``c``)."""
        if "lib" not in self.state:
            self.state["lib"] = self.load()
        return self.state["lib"]                # type: ignore[return-value]
