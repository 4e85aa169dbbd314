"""A study's whole loop as one co-simulation FMU (FMI 2.0 or 3.0): the compiled engine's C
(orchestrator.compiled: one unit per component core and the loop unit, the very text its cached
library is built from) behind the sampled-model semantics every exported FMU shares
(c/sampled_instance.c), with the study's base step as the sample period.

The model core written here only holds the loop's state by value (base step k, the published
outputs, the inputs, every component's state) and steps it: at t_k = t0 + k h the FMU's outputs
are the loop's row k (``agc_sample_phase``: continuous outputs g(x_k), then the sampled
components due at k, in the system's order), and doStep commits step 4 (``agc_continuous_phase``:
the continuous components step to k + 1). The recorded signals of the study's run at t_k are
therefore the FMU's outputs at t_k.

Ports: the study's ``[exports]`` when it declares them (an exported input is written into its
inner inputs before the components due read them; its start is the study's value), else every
signal the study records (``component.output``) as an output and no input.

Parameters: every run-time parameter of a C core that a master can change without another build
is an FMU parameter named ``component.parameter``, fixed (set before the initialization ends: a
core may cache what it derives from one during the run). A parameter is kept compiled in when
changing it changes what is
built: the generated defines (a buffer sized for a delay, a horizon), a value the core derives in
Python from it, or an output at t0 (``tunable_parameters`` perturbs each and compares); those are
named in the export's note. The seed and the initial outputs are compiled in.
"""
from __future__ import annotations

import ctypes
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from agrobot.orchestrator.build import System, build_system
from agrobot.orchestrator.compiled import CompiledRefused, CompiledSimulation, cores_of
from agrobot.orchestrator.compiled.cores import c_array, c_core, core_parameters, description_of
from agrobot.orchestrator.compiled.simulation import refusal
from agrobot.orchestrator.component import ComponentError
from agrobot.orchestrator.composite import exported_ports, inner_feedthrough
from agrobot.orchestrator.errors import InputError
from agrobot.orchestrator.resolver import resolve
from agrobot.orchestrator.study import Study

from .packaging import PackagingError
from .sampled_fmu import WRAPPERS, SampledModel, build_fmu, c_strings, token_of

ALIGN = 16          # bytes: each component's state starts on this boundary in the loop's state


class LoopExportError(InputError):
    """The loop FMU cannot be written where asked (the message names the option and why)."""


def identifier(name: str) -> str:
    """A C identifier (the FMU's modelIdentifier) from a study name."""
    ident = re.sub(r"\W", "_", name)
    return ident if ident[:1].isalpha() else f"loop_{ident}"


@dataclass
class Ports:
    """The FMU's ports and where they sit in the loop."""

    inputs: list[tuple[str, str, str]]           # (name, unit, description)
    outputs: list[tuple[str, str, str]]
    out_at: list[int]                            # the published value each output reads
    slots: list[tuple[int, int]]                 # (loop input slot, FMU input) written before each sample
    starts: list[float]                          # the inputs' starts
    dependencies: dict[str, list[str]]           # output -> the inputs it reads in the same instant
    note: str                                    # the line saying which ports were chosen


def loop_ports(system: System, lay, declared: str = "the study's [exports]") -> Ports:
    """The ports of the loop's FMU: the study's [exports] (checked and declared as for a
    subsystem, orchestrator.composite), else every recorded signal as an output."""
    study, nodes = system.study, system.nodes
    idx = {n: i for i, n in enumerate(lay.names)}

    def where(comp: str, port: str, causality: str) -> int:
        """The port's place in the loop's published values (outputs) or inputs (the C core's order)."""
        names = [v.name for v in nodes[comp].component.variables if v.causality == causality]
        return (lay.pub if causality == "output" else lay.inp)[idx[comp]] + names.index(port)

    exports = study.exports
    if exports is None or not (exports.inputs or exports.outputs):
        declared_as = {f"{n}.{v.name}": v for n, node in nodes.items() for v in node.component.variables}
        outputs = [(c, declared_as[c].unit or "1", declared_as[c].description) for c, _ in lay.columns]
        return Ports([], outputs, [at for _, at in lay.columns], [], [], {}, (
            f"ports: every signal the study records ({len(outputs)} outputs, no input): it declares no [exports] "
            f"(declare [exports] outputs/inputs to choose the FMU's ports)"))
    variables, _ = exported_ports(system, study, study.where)
    inputs = [(v.name, v.unit or "1", v.description) for v in variables if v.causality == "input"]
    outputs = [(v.name, v.unit or "1", v.description) for v in variables if v.causality == "output"]
    out_at = [where(*exports.output_source(port), "output") for port, _, _ in outputs]
    slots, starts = [], []
    for j, (port, _, _) in enumerate(inputs):
        targets = exports.input_targets(port)
        # the study's value of the first target (a constant it gives, else the input's start)
        starts.append(float(nodes[targets[0][0]].component.u[targets[0][1]]) if targets
                      else float(exports.inputs[port].start))
        slots += [(where(comp, inp, "input"), j) for comp, inp in targets]
    # continuous components publish from their state: only connections and sampled feedthrough carry
    # an input to an output within the instant
    reach = inner_feedthrough(system, exports)
    return Ports(inputs, outputs, out_at, slots, starts, {o: list(reach.get(o, ())) for o, _, _ in outputs},
                 f"ports: {declared} ({len(inputs)} inputs, {len(outputs)} outputs)")


@dataclass
class CompiledLoop:
    """What the compiled engine builds of the loop: its C units (``c{i}.c`` per component, ``loop.c``),
    the source files they include, the simulation (terminated: its layout, library and key stay), the
    initial parameter, published and input vectors, and each component's state size in bytes."""

    units: dict[str, str]
    files: list[str]
    sim: CompiledSimulation
    par: np.ndarray
    pub0: np.ndarray
    in0: np.ndarray
    sizes: list[int]


def compiled_loop(system: System) -> CompiledLoop:
    """The loop of ``system`` compiled by the compiled engine (or found in its cache).
    CompiledRefused names the components without a C core."""
    cores, missing = cores_of(system)
    if missing:             # (a study paced in real time is exported too: the FMU is paced by its master)
        raise CompiledRefused(f"{system.study.path}: export-fmu: {refusal(system, missing)}; only a study whose "
                              f"every component has a C core becomes one FMU (export-ssp writes one FMU per component)")
    units, _, files = CompiledSimulation.sources(system, cores)
    sim = CompiledSimulation(system, cores)           # compiles the shape (or finds it cached): the states' sizes
    try:
        par, pub0, in0 = sim.initial_vectors()
    finally:
        sim.terminate()
    sizes = []
    for i in range(len(sim.layout.names)):
        size = getattr(sim.lib, f"agc_size_{i}")
        size.restype = ctypes.c_ulong
        sizes.append(int(size()))
    return CompiledLoop(units, files, sim, par, pub0, in0, sizes)



@dataclass
class Tunable:
    """The loop's parameters a master may set: (FMU name, index in the loop's parameter vector,
    value, unit, description), and those compiled in."""

    parameters: list[tuple[str, int, float, str, str]]
    fixed: list[str]


def _built_from(system: System, name: str) -> tuple:
    """What building component ``name`` makes of its parameters: the core's defines, its run-time
    values, its outputs at t0."""
    node = system.nodes[name]
    node.component.initialize(float(system.study.study.start_time), node.step)
    core = c_core(system, name)
    return core.source, [v for _, v in core.parameters], dict(node.component.y)


def tunable_parameters(system: System, names: list[str]) -> Tunable:
    """Each C core's run-time parameter, in the loop's order (``names``), tunable when a change of
    it (x 1.1 + 0.01) leaves ``_built_from`` as it was; restored after."""
    tunable, fixed, at = [], [], 0
    for name in names:
        comp = system.nodes[name].component
        listed = core_parameters(comp, description_of(comp), "")
        base = _built_from(system, name)
        for j, (pname, value, unit, text) in enumerate(listed):
            if pname not in comp.p:                 # the core's own (a seed): compiled in
                continue
            try:
                comp.p[pname] = value * 1.1 + 0.01
                built = _built_from(system, name)
                same = built[0] == base[0] and _equal(built[1], base[1], skip=j) and _equal_outputs(built[2], base[2])
            except (ComponentError, ValueError, ArithmeticError, TypeError, RuntimeError):
                same = False   # a value the component refuses (a switch, a count): kept as built
            finally:
                comp.p[pname] = value
            if same:
                tunable.append((f"{name}.{pname}", at + j, value, unit, text))
            else:
                fixed.append(f"{name}.{pname}")
        _built_from(system, name)                   # as the study built it
        at += len(c_core(system, name).parameters)
    return Tunable(tunable, fixed)


def _equal(a: list, b: list, skip: int) -> bool:
    return len(a) == len(b) and all(x == y for i, (x, y) in enumerate(zip(a, b)) if i != skip)


def _equal_outputs(a: dict, b: dict) -> bool:
    return a.keys() == b.keys() and all(np.array_equal(np.asarray(a[k]), np.asarray(b[k])) for k in a)

def state_offsets(sizes: list[int]) -> tuple[list[int], int]:
    """(each component's offset in the loop's state, the state's bytes): the states one after the
    other, each of max(size, 1) bytes rounded up to a multiple of ALIGN."""
    offsets, total = [], 0
    for size in sizes:
        offsets.append(total)
        total += -(-max(size, 1) // ALIGN) * ALIGN
    return offsets, total


def fmu_units(loop: CompiledLoop) -> dict[str, str]:
    """The compiled engine's units as the FMU's sources (``agc_c{i}.c``, ``agc_loop.c``), each
    component's with a compile-time check that its ModelState fits the bytes the loop holds for it."""
    units = {f"agc_c{i}.c": loop.units[f"c{i}.c"] + f"\n/* the loop FMU holds this state in {size} bytes */\n"
             f"typedef char agc_state_fits_{i}[(sizeof(ModelState) <= {size}) ? 1 : -1];\n"
             for i, size in enumerate(loop.sizes)}
    units["agc_loop.c"] = loop.units["loop.c"]
    return units


def _core_tables(ident: str, system: System, ports: Ports, loop: CompiledLoop, offsets: list[int],
                 tunable: Tunable) -> list[str]:
    """The model core's head: the sampled-model macros (the tunable parameters, the ports, the base
    step as period), the loop's phases, and its constant tables (parameters, where each tunable one
    sits among them, initial values, state offsets, the published value each output reads, the
    input slots each FMU input writes)."""
    s, n = system.study.study, len(offsets)
    inputs, outputs, slots = ports.inputs, ports.outputs, ports.slots
    tuned = tunable.parameters
    return [
        f"/* {ident}: the whole loop of {Path(str(system.study.path)).name} ({n} components), one base step "
        f"{float(s.base_step)!r} s a sample (generated by fmu_export.loop_fmu) */",
        "#include <math.h>", "#include <stdlib.h>", "#include <string.h>",
        f"#define MODEL_NPAR {len(tuned)}", "#define MODEL_PAR_FIXED 1", f"#define MODEL_NIN {len(inputs)}", f"#define MODEL_NOUT {len(outputs)}",
        f"#define MODEL_PERIOD {float(s.base_step)!r}",
        f"static const double MODEL_PAR_START[MODEL_NPAR + 1] = {{{c_array([t[2] for t in tuned]) or '0.0'}}};",
        f"static const char *const MODEL_PAR_NAMES[MODEL_NPAR + 1] = {{{c_strings(t[0] for t in tuned)}}};",
        f"static const int LOOP_TUNE[MODEL_NPAR + 1] = {{{', '.join(str(t[1]) for t in tuned) or '0'}}};",
        f"#define LOOP_NPAR {max(len(loop.par), 1)}",
        f"static const char *const MODEL_IN_NAMES[MODEL_NIN + 1] = {{{c_strings(i[0] for i in inputs)}}};",
        f"static const char *const MODEL_OUT_NAMES[MODEL_NOUT + 1] = {{{c_strings(o[0] for o in outputs)}}};",
        f"static const double LOOP_IN_START[MODEL_NIN + 1] = {{{c_array(ports.starts) or '0.0'}}};",
        "#define MODEL_IN_START LOOP_IN_START",
        "void agc_start_all(void *const *st, const double *par);",
        "void agc_sample_phase(void *const *st, const double *par, double *pub, double *in, long k);",
        "void agc_continuous_phase(void *const *st, const double *par, double *pub, double *in, long k);",
        f"#define LOOP_N {n}",
        f"static const double LOOP_PAR[LOOP_NPAR] = {{{c_array(loop.par) or '0.0'}}};",
        f"static const double LOOP_PUB0[{max(len(loop.pub0), 1)}] = {{{c_array(loop.pub0) or '0.0'}}};",
        f"static const double LOOP_IN0[{max(len(loop.in0), 1)}] = {{{c_array(loop.in0) or '0.0'}}};",
        f"static const unsigned long LOOP_OFFSET[LOOP_N] = {{{', '.join(map(str, offsets))}}};",
        f"static const int LOOP_OUT[MODEL_NOUT + 1] = {{{', '.join(map(str, ports.out_at)) or '0'}}};",
        f"#define LOOP_NSLOT {len(slots)}",
        f"static const int LOOP_SLOT[LOOP_NSLOT + 1][2] = "
        f"{{{', '.join(f'{{{a}, {b}}}' for a, b in slots) or '{0, 0}'}}};"]


def _core_functions(lay, total: int) -> list[str]:
    """The model core's state (base step k, the loop's parameters with the tunable ones written in,
    published values, inputs, the components' states by value) and its functions: start, and a
    sample (the tunable parameters and the FMU inputs written into their slots, the sample phase,
    the outputs read, the continuous phase to k + 1)."""
    return [
        "typedef struct {",
        "    long k;                                   /* the base step whose row the next sample gives */",
        "    double par[LOOP_NPAR];                    /* the loop's parameters, the tunable ones as set */",
        f"    double pub[{max(lay.n_pub, 1)}], in[{max(lay.n_in, 1)}];",
        f"    unsigned char mem[{max(total, ALIGN)}] __attribute__((aligned({ALIGN})));   /* the components' states */",
        "} ModelState;",
        "static void loop_states(ModelState *s, void **st) {",
        "    for (int i = 0; i < LOOP_N; i++) st[i] = s->mem + LOOP_OFFSET[i];",
        "}",
        "static void loop_tuned(ModelState *s, const double *p) {",
        "    for (int i = 0; i < MODEL_NPAR; i++) s->par[LOOP_TUNE[i]] = p[i];",
        "}",
        "static void model_start(ModelState *s, const double *p) {",
        "    void *st[LOOP_N];",
        "    memset(s, 0, sizeof *s);",
        "    memcpy(s->par, LOOP_PAR, sizeof s->par);",
        "    loop_tuned(s, p);",
        f"    memcpy(s->pub, LOOP_PUB0, sizeof(double) * {lay.n_pub});",
        f"    memcpy(s->in, LOOP_IN0, sizeof(double) * {lay.n_in});",
        "    loop_states(s, st);",
        "    agc_start_all(st, s->par);",
        "}",
        "static void model_sample(ModelState *s, const double *p, const double *in, double *out) {",
        "    void *st[LOOP_N];",
        "    loop_tuned(s, p);",
        "    loop_states(s, st);",
        "    for (int j = 0; j < LOOP_NSLOT; j++) s->in[LOOP_SLOT[j][0]] = in[LOOP_SLOT[j][1]];",
        "    agc_sample_phase(st, s->par, s->pub, s->in, s->k);",
        "    for (int o = 0; o < MODEL_NOUT; o++) out[o] = s->pub[LOOP_OUT[o]];",
        "    agc_continuous_phase(st, s->par, s->pub, s->in, s->k);",
        "    s->k++;",
        "}", ""]


def loop_model(system: System, declared: str = "the study's [exports]") -> tuple[SampledModel, str]:
    """(the whole loop of ``system`` as a sampled model, the line saying which ports it has:
    ``declared`` says where its [exports] come from). CompiledRefused names the components
    without a C core."""
    loop = compiled_loop(system)
    lay = loop.sim.layout
    offsets, total = state_offsets(loop.sizes)
    ports = loop_ports(system, lay, declared)
    deps = {o: ports.dependencies.get(o, []) for o, _, _ in ports.outputs}
    s = system.study.study
    ident = identifier(s.name)
    units = fmu_units(loop)
    tunable = tunable_parameters(system, lay.names)
    body = "\n".join(_core_tables(ident, system, ports, loop, offsets, tunable) + _core_functions(lay, total))
    token = token_of(body + "".join(units.values()) + loop.sim.key)
    core = body.replace("#define MODEL_NPAR ", f'#define MODEL_TOKEN "{token}"\n#define MODEL_NPAR ', 1)
    description = (f"the whole loop of {Path(str(system.study.path)).name} ({', '.join(lay.names)}), compiled from the "
                   f"components' C cores; one sample every base step of {float(s.base_step)!r} s")
    fixed = ", ".join(tunable.fixed[:6]) + (f" and {len(tunable.fixed) - 6} more" if len(tunable.fixed) > 6 else "")
    note = ports.note + (f"; one sample every {float(s.base_step)!r} s (the study's base step, or a whole multiple of "
                         f"it, as the communication step); {len(tunable.parameters)} parameters to set before the "
                         f"initialization ends (component.parameter); compiled in: the seed" + (f", {fixed}" if fixed else "")
                         + " (--set them and export again)")
    parameters = [(name, value, unit, text) for name, _, value, unit, text in tunable.parameters]
    model = SampledModel(ident, token, description, float(s.base_step), parameters, ports.inputs, ports.outputs, deps, core,
                         sorted(set(loop.files)), units,
                         ports.starts if ports.inputs else None, float(s.stop_time), "fixed")
    return model, note


def subsystem(study: Study, components: list[str]) -> Study:
    """The named components of ``study`` as a study of their own (orchestrator.model's
    ``extract``): every input not fed inside the group an exported input (start: the study's
    constant or the input's start), every output of the group an exported output, named
    ``component_port``."""
    unknown = [n for n in components if n not in study.components]
    if unknown or not components:
        raise LoopExportError(f"{study.path}: --components {','.join(components)}: "
                              + (f"no component named {', '.join(unknown)}; " if unknown else "none given; ")
                              + f"expected names of {', '.join(study.components)}")
    return resolve(study).extract(components, name=f"{study.study.name}_{'_'.join(components)}")


def export_loop(study: Study, fmi_version: int = 2, components: list[str] | None = None) -> tuple[bytes, str]:
    """The whole loop of ``study`` (or the subsystem of ``components``) as one FMU: (the archive's
    bytes, the ports line); agrobot.api.export_fmu writes it."""
    if fmi_version not in WRAPPERS:
        raise LoopExportError(f"--fmi-version {fmi_version}: expected one of {', '.join(map(str, WRAPPERS))}")
    if components is not None:
        study = subsystem(study, components)
    try:
        model, note = loop_model(build_system(resolve(study)), "the study's [exports]" if components is None else
                                 "the subsystem's boundary: the inputs its components do not feed each other, "
                                 "every output, named component_port")
        return build_fmu(model, fmi_version), note
    except PackagingError as exc:
        raise LoopExportError(str(exc)) from None