"""Build the tests' own FMUs from C sources (nothing is downloaded): gcc straight to a shared
library, and every FMI function fmpy binds that the source does not define becomes a stub
returning an error, so small sources stay small."""
from __future__ import annotations

import inspect
import re
import subprocess
import zipfile
from pathlib import Path

SOURCES = Path(__file__).resolve().parent / "fmu_sources"


def build_test_fmu(name: str, out_dir: Path, xml_edit=None) -> Path:
    """``tests/fmu_sources/<name>/`` (one C file and modelDescription.xml) -> ``out_dir/<name>.fmu``."""
    import fmpy
    from fmpy.fmi2 import FMU2Model, FMU2Slave
    from fmpy.fmi3 import FMU3Model, FMU3Slave

    folder = SOURCES / name
    xml = (folder / "modelDescription.xml").read_text()
    if xml_edit is not None:
        xml = xml_edit(xml)
    fmi3 = 'fmiVersion="3.0"' in xml
    model_exchange = "<ModelExchange" in xml and "<CoSimulation" not in xml
    identifier = re.search(r'modelIdentifier="([^"]+)"', xml).group(1)
    sources = sorted(folder.glob("*.c"))
    defined = {n for src in sources for n in re.findall(r"\b(fmi[23]\w+)\(", src.read_text())}
    cls = {(False, False): FMU2Slave, (False, True): FMU2Model, (True, False): FMU3Slave,
           (True, True): FMU3Model}[(fmi3, model_exchange)]
    prefix = "fmi3" if fmi3 else "fmi2"
    stubs = [f"int {n}(void) {{ return 3; }}" for n, _ in inspect.getmembers(cls)
             if n.startswith(prefix) and n not in defined]
    work = out_dir / f"{name}.build"
    work.mkdir(parents=True, exist_ok=True)
    (work / "stubs.c").write_text("\n".join(stubs) + "\n")
    platform = fmpy.platform_tuple if fmi3 else fmpy.platform
    binary = work / "binaries" / platform / f"{identifier}.so"
    binary.parent.mkdir(parents=True, exist_ok=True)
    subprocess.run(["gcc", "-O2", "-shared", "-fPIC", "-o", str(binary), *map(str, sources), str(work / "stubs.c"),
                    "-lm"], check=True)
    out = out_dir / f"{name}.fmu"
    with zipfile.ZipFile(out, "w") as zf:
        zf.writestr("modelDescription.xml", xml)
        zf.write(binary, binary.relative_to(work).as_posix())
    return out
