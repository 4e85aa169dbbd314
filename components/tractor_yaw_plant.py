"""Tractor yaw plant: LPV yaw dynamics in the longitudinal speed plus pose kinematics.

Yaw dynamics (``model``): ``bicycle`` (2nd order), ``rlf`` (3rd, relaxation length front),
``rlfr`` (4th, front and rear) from the equations of motion (see models.yaw_dynamics), or
``transfer_function`` (num/den, default the paper's empirical G_2nd = 291/(s^2+10.9s+242),
not speed dependent; lateral velocity then taken kinematically, v_y = l_r gamma).

Default ``rlf``: with the Table values it is stable at every speed and at 2 m/s its poles
(-5.9 +- 13.7j) lie next to G_2nd's (-5.45 +- 14.6j). ``rlfr`` with the Table values has a weakly
growing rear-relaxation mode near 1.65 Hz (Re ~ +0.03 1/s): a study naming only ``model = "rlfr"``
gets ``parameter_set = "rlfr_identified"`` (stable, G_RLFR's poles at 2 m/s; models.paper_models);
``parameter_set = "table"`` keeps the Table values and building such a study warns
(UnstableModelWarning) with the pole. Values a study sets (C_f, ...) win over the set.

Integration: over each step the dynamics are exact for delta and v_x held (ZOH, matrix
exponential). The pose at the CG follows (paper eq. 2)::

    dx/dt = v_x cos(psi) - v_y sin(psi),  dy/dt = v_x sin(psi) + v_y cos(psi),  dpsi/dt = gamma

integrated with the midpoint rule; the rear-axle point R (GPS antenna) is CG - l_r (cos psi, sin psi).
Below ``min_speed`` the dynamics use min_speed (the slip equations divide by v_x) and the yaw rate
is scaled by v_x/min_speed, so a tractor at rest does not turn.

Extensions (off by default; each is an entry of the diagnosis catalogue, see src/agrobot/diagnosis/effects/):
``steer_angle_offset`` (the tyres see delta + offset: a wheel-angle sensor zeroed wrongly),
``cornering_speed_slope`` (C_f, C_r scaled by 1 + k (v_x - v_ref)), ``slope_angle`` with
``slope_downhill_heading`` (side slope: a_lat = g sin(phi) sin(psi_d - psi) at the CG, physical
models only), ``antenna_forward``/``antenna_left`` (GPS antenna = R + lever arm in the body frame)
and ``tyre_friction`` with ``tyre_shape`` (tyre saturation: each axle's force follows the simplified
Magic Formula of models.tyre instead of C alpha; physical models only; integrated by Rosenbrock
sub-steps of at most 2 ms instead of the matrix exponential) and ``tyre_friction_ratio`` rho (the
front axle's peak is mu F_zf, the rear's rho mu F_zr: the axle that lets go first sets the limit
understeer, identification.axle_friction; within FRICTION_RATIO_BOUNDS). The C core models none of
the tyre saturation: the compiled engine refuses a study that sets it and ``auto`` runs it in Python.

Steering geometry (``steering_geometry``): ``w`` (default) drives the dynamics by the wheel angle
delta, the linear single-track model whose front slip is alpha_f = delta - (v_y + l_f gamma) / v_x;
``tan`` by the equivalent angle tan(delta), alpha_f = tan(delta) - (v_y + l_f gamma) / v_x: the
wheel's heading and its velocity's both taken as tangents, so a turn without slip (alpha_f = alpha_r
= 0, v_y = l_r gamma) is the Ackermann one at any lock,

    gamma = v_x tan(delta) / L,        and in a steady turn  gamma = v_x tan(delta) / (L + K v_x^2),

while for small angles (tan delta = delta + delta^3 / 3) the model, and its linearisation about the
straight line (d tan / d delta = 1 at 0), are the linear one. delta is clipped to +-MAX_TAN_ANGLE (as
identification.driving.YawModel's wheel angle); the offset is added before the tangent.

Terrain (models.terrain): the ground is the plane of ``slope_angle`` and ``slope_downhill_heading``,
or the height grid of ``terrain_file``; at the CG it gives the tractor's roll and pitch (outputs)
and the lateral pull a_lat = P . (-sin psi, cos psi) of the in-plane gravity P. The GPS antenna
stands ``antenna_height`` above R: its horizontal position is R + Rz(psi) Ry(-pitch) Rx(roll)
(forward, left, height), h sin(roll) downhill on a side slope. The dynamics stay those of the
horizontal projection (the slope shortens distances by cos(phi): 1.5 % at 10 deg), and the antenna
velocity leaves out the attitude's own rates (roll and pitch change only as the heading turns).
"""
from __future__ import annotations

import math
import warnings
from pathlib import Path

import numpy as np

from agrobot.orchestrator.compiled.cores import CoreDescription, NoCCore, c_array
from agrobot.orchestrator.component import Component, ComponentError, inp, out, par
from agrobot.orchestrator.units import FILE_UNIT

from .models.loop_blocks import Block, Ground
from .models.paper_models import G_2ND
from .models.terrain import GRAVITY, attitude, ground_of, lever_offset, slope_pull
from .models.tyre import FRICTION_RATIO_BOUNDS, ros2_step
from .models.yaw_dynamics import (PHYSICAL_MODELS, TractorParameters, controllable_canonical, cornering_scale,
                                  lateral_disturbance_column, state_space, with_cornering_scale, zoh_discretize)

MODELS = PHYSICAL_MODELS + ("transfer_function",)
CHECKED_SPEEDS = (0.5, 1.0, 1.5, 2.0, 2.5, 3.0)
STEERING_GEOMETRIES = ("w", "tan")     # the dynamics driven by delta, or by tan(delta) (the Ackermann turn)
MAX_TAN_ANGLE = 1.3                    # rad: |delta| clipped there under "tan" (tan 1.3 = 3.6)


def steer_input(delta, geometry: str = "w"):
    """The angle driving the yaw dynamics: delta under "w", tan(delta) (delta clipped to
    +-MAX_TAN_ANGLE) under "tan"; a float or an array as given."""
    if geometry != "tan":
        return delta
    if isinstance(delta, float):
        return math.tan(min(max(delta, -MAX_TAN_ANGLE), MAX_TAN_ANGLE))
    return np.tan(np.clip(delta, -MAX_TAN_ANGLE, MAX_TAN_ANGLE))



def _tan_defines(comp) -> str:
    """STEER_TAN (1: the dynamics driven by tan(delta)) and MAX_TAN_ANGLE for the C core."""
    return f"#define STEER_TAN {int(comp.p['steering_geometry'] == 'tan')}\n#define MAX_TAN_ANGLE {MAX_TAN_ANGLE!r}\n"


def _plant_compiled(comp, period: float) -> str:
    """The yaw model as C: its index among PHYSICAL_MODELS, or a transfer function's canonical form."""
    model = comp.p["model"]
    if model == "transfer_function":          # yaw rate from num/den in controllable canonical form
        A, B, C = controllable_canonical(comp.p["tf_num"], comp.p["tf_den"])
        n = A.shape[0]
        return (f"#define YAW_MODEL 3\n#define TF_ORDER {n}\nstatic const double TF_A[{n * n}] = {{{c_array(A)}}};\n"
                f"static const double TF_B[{n}] = {{{c_array(B)}}};\nstatic const double TF_C[{n}] = {{{c_array(C)}}};\n"
                + _tan_defines(comp))
    if model not in PHYSICAL_MODELS:
        raise NoCCore(f"model = {model!r} has no C form (its core covers {', '.join(PHYSICAL_MODELS)} and "
                      f"transfer_function)")
    return f"#define YAW_MODEL {PHYSICAL_MODELS.index(model)}\n" + _tan_defines(comp)


def _plant_values(comp) -> dict[str, float]:
    """The core's m, I, l_f, l_r, C_f, C_r, sigma_f, sigma_r: the named set resolved, cornering scales applied."""
    params = TractorParameters.of(comp.p)
    return {k: getattr(params, k) for k in ("m", "I", "l_f", "l_r", "C_f", "C_r", "sigma_f", "sigma_r")}

class UnstableModelWarning(UserWarning):
    """The plant's linear yaw model has a pole in the right half plane."""


def unstable_modes(model: str, params: TractorParameters, speeds=CHECKED_SPEEDS) -> list[tuple[float, complex]]:
    """(speed, pole with the largest real part) at each speed where that real part is > 0."""
    out = []
    for v in speeds:
        poles = np.linalg.eigvals(state_space(model, params, v)[0])
        worst = poles[np.argmax(poles.real)]
        if worst.real > 1e-9:
            out.append((v, complex(worst)))
    return out


def _yaw_dynamics(comp, speed: float):
    """(A, B, C, v_y row, parameters) of the plant's yaw dynamics at v (models.yaw_dynamics; v_y =
    l_r gamma for a transfer-function model), as its step uses them."""
    p = comp.p
    params = TractorParameters.of(p)
    if p["model"] == "transfer_function":
        Ay, By, Cy = controllable_canonical(p["tf_num"], p["tf_den"])
        return Ay, By, Cy, params.l_r * Cy, params
    if float(p["cornering_speed_slope"]):
        params = with_cornering_scale(params, cornering_scale(speed, p["cornering_speed_slope"],
                                                              p["cornering_reference_speed"]))
    Ay, By, Cy = state_space(p["model"], params, speed)
    return Ay, By, Cy, np.eye(len(By))[0], params


def _on_the_plane(p, heading: float) -> dict[str, float]:
    """Roll, pitch, the pull across the heading and the antenna's lever (east, north) of a plant
    heading ``heading`` on its plane (models.terrain, as the plant's step computes them)."""
    gx, gy = ground_of(p["slope_angle"], p["slope_downhill_heading"]).gradient(0.0, 0.0)
    pe, pn = slope_pull(gx, gy)
    roll, pitch = attitude(gx, gy, heading)
    ox, oy = lever_offset(roll, pitch, heading, p["antenna_forward"], p["antenna_left"], p["antenna_height"])
    return {"roll": roll, "pitch": pitch, "pull": -pe * math.sin(heading) + pn * math.cos(heading),
            "lever_east": ox, "lever_north": oy}


def _per_heading(p, eps: float = 1e-6) -> dict[str, float]:
    """d/d psi at psi = 0 of _on_the_plane's values (central differences)."""
    up, down = _on_the_plane(p, eps), _on_the_plane(p, -eps)
    return {k: (up[k] - down[k]) / (2 * eps) for k in up}


def _affine(w: list, b: list, d: float) -> list:
    """w + b d element by element, on Python floats (``_affineN``: also written into the array
    ``held``, unrolled for N states)."""
    return [wi + bi * d for wi, bi in zip(w, b)]


def _affine2(w: list, b: list, d: float, held) -> list:
    w0, w1 = w
    b0, b1 = b
    z0, z1 = w0 + b0 * d, w1 + b1 * d
    held[0] = z0
    held[1] = z1
    return [z0, z1]


def _affine3(w: list, b: list, d: float, held) -> list:
    w0, w1, w2 = w
    b0, b1, b2 = b
    z0, z1, z2 = w0 + b0 * d, w1 + b1 * d, w2 + b2 * d
    held[0] = z0
    held[1] = z1
    held[2] = z2
    return [z0, z1, z2]


def _affine4(w: list, b: list, d: float, held) -> list:
    w0, w1, w2, w3 = w
    b0, b1, b2, b3 = b
    z0, z1, z2, z3 = w0 + b0 * d, w1 + b1 * d, w2 + b2 * d, w3 + b3 * d
    held[0] = z0
    held[1] = z1
    held[2] = z2
    held[3] = z3
    return [z0, z1, z2, z3]


def _affine_held(w: list, b: list, d: float, held) -> list:
    z = _affine(w, b, d)
    held[:] = z
    return z


_AFFINE = {2: _affine2, 3: _affine3, 4: _affine4}     # unrolled for the physical models' states


class TractorYawPlant(Component):
    sampled = False
    roles = ("yaw_plant",)
    c_core = CoreDescription(Path(__file__).with_suffix(".c"), _plant_compiled,     # its C model core, beside this file
                             ("model", "parameter_set", "tf_num", "tf_den", "cornering_scale_front",
                              "cornering_scale_rear", "steering_geometry"), ("terrain_file", "tyre_friction", "tyre_shape",
                                                                         "tyre_friction_ratio"), _plant_values)
    variables = (
        inp("steer_angle", "rad", 0.0, "front wheel steering angle delta"),
        inp("speed", "m/s", 0.0, "longitudinal speed v_x of the CG"),
        par("model", "", "rlf", "yaw model: bicycle, rlf, rlfr or transfer_function"),
        par("m", "kg", 700.0, "mass"),
        par("I", "kg m2", 280.0, "yaw moment of inertia (paper: I = m l_f l_r)"),
        par("l_f", "m", 1.0, "front axle to CG"),
        par("l_r", "m", 0.4, "rear axle to CG"),
        par("parameter_set", "", "", "named C_f, C_r, sigma_f, sigma_r: 'table' or 'rlfr_identified' "
            "(empty: rlfr_identified for rlfr, table otherwise; see models.paper_models)"),
        par("C_f", "N/rad", None, "front cornering stiffness (unset: from parameter_set)"),
        par("C_r", "N/rad", None, "rear cornering stiffness (unset: from parameter_set)"),
        par("sigma_f", "m", None, "front relaxation length (unset: from parameter_set)"),
        par("sigma_r", "m", None, "rear relaxation length (unset: from parameter_set)"),
        par("cornering_scale_front", "1", 1.0, "factor on C_f (a relative variation, whatever the set)"),
        par("cornering_scale_rear", "1", 1.0, "factor on C_r (a relative variation, whatever the set)"),
        par("tf_num", "", list(G_2ND.num), "transfer_function model: numerator, highest power first"),
        par("tf_den", "", list(G_2ND.den), "transfer_function model: denominator"),
        par("min_speed", "m/s", 0.1, "regularisation speed for the slip equations"),
        par("x0", "m", 0.0, "initial CG east position"),
        par("y0", "m", 0.0, "initial CG north position"),
        par("psi0", "rad", 0.0, "initial heading (from east, counter-clockwise)"),
        par("speed_cache_resolution", "m/s", 1e-3, "speeds closer than this share one discretisation"),
        par("steer_angle_offset", "rad", 0.0, "extension: tyres see steer_angle + offset"),
        par("steering_geometry", "", "w", "the dynamics driven by the wheel angle delta ('w') or by tan(delta) "
            "('tan': the turn without slip is v tan(delta) / L at any lock)"),
        par("cornering_speed_slope", "s/m", 0.0, "extension: C_f, C_r x (1 + k (v_x - v_ref))"),
        par("cornering_reference_speed", "m/s", 2.0, "extension: v_ref of the cornering scaling"),
        par("slope_angle", "rad", 0.0, "extension: side slope of the field plane"),
        par("slope_downhill_heading", "rad", 0.0, "extension: azimuth of the fall line (from east, CCW)"),
        par("antenna_forward", "m", 0.0, "extension: GPS antenna ahead of R"),
        par("antenna_left", "m", 0.0, "extension: GPS antenna left of R"),
        par("antenna_height", "m", 0.0, "GPS antenna height above the ground at R (2-4 m on tractors)"),
        par("terrain_file", FILE_UNIT, "", "the ground as a height grid: CSV x, y, z in metres, mission frame "
            "(empty: the plane of slope_angle)"),
        par("tyre_friction", "1", 0.0, "extension: tyre friction mu of the Magic Formula (0 = linear tyres)"),
        par("tyre_shape", "1", 1.3, "extension: Magic Formula shape factor C (1 < C < 2: a peak; 0 < C < 1: none)"),
        par("tyre_friction_ratio", "1", 1.0, "extension: the rear tyres' peak friction over the front's, mu_r / mu_f "
            "(tyre_friction is the front's; 1: one friction on both axles)"),
        out("yaw_rate", "rad/s", 0.0, "yaw rate gamma"),
        out("lateral_velocity", "m/s", 0.0, "lateral velocity v_y of the CG"),
        out("heading", "rad", 0.0, "yaw angle psi"),
        out("x_cg", "m", 0.0, "CG east position"),
        out("y_cg", "m", 0.0, "CG north position"),
        out("x_rear", "m", 0.0, "rear-axle point R east position (GPS antenna)"),
        out("y_rear", "m", 0.0, "rear-axle point R north position"),
        out("vel_east_rear", "m/s", 0.0, "velocity of R, east"),
        out("vel_north_rear", "m/s", 0.0, "velocity of R, north"),
        out("x_antenna", "m", 0.0, "GPS antenna east position (R + lever arm)"),
        out("y_antenna", "m", 0.0, "GPS antenna north position"),
        out("vel_east_antenna", "m/s", 0.0, "GPS antenna velocity, east"),
        out("vel_north_antenna", "m/s", 0.0, "GPS antenna velocity, north"),
        out("slope_pull_east", "m/s2", 0.0, "the side slope's in-plane gravity g sin(phi) cos(psi_d), for a "
            "trailed implement"),
        out("slope_pull_north", "m/s2", 0.0, "g sin(phi) sin(psi_d)"),
        out("roll", "rad", 0.0, "roll on the ground at the CG, positive: left side up"),
        out("pitch", "rad", 0.0, "pitch on the ground at the CG, positive: nose up"),
    )
    feedthrough = {}

    def __init__(self, name, parameters=None, rng=None) -> None:
        super().__init__(name, parameters, rng)
        self._check_friction_ratio()
        if self.p["model"] in PHYSICAL_MODELS:
            try:
                unstable = unstable_modes(self.p["model"], self._parameters())
            except (ValueError, np.linalg.LinAlgError):
                return                                   # initialize() names the bad value
            if unstable:
                v, pole = unstable[0]
                warnings.warn(UnstableModelWarning(
                    f"{name}: the {self.p['model']} model with parameter set "
                    f"{self.p['parameter_set'] or 'default'!r} has an unstable mode: pole {pole.real:+.3f} "
                    f"{pole.imag:+.2f}j 1/s at {v:g} m/s (unstable at {', '.join(f'{s:g}' for s, _ in unstable)} m/s); "
                    f"the paper's identified G_RLFR has none (parameter_set = 'rlfr_identified' is stable)"),
                    stacklevel=2)

    def _check_friction_ratio(self) -> None:
        """ComponentError (the study's file and field named by build_system) for a tyre_friction_ratio
        that is not a number within FRICTION_RATIO_BOUNDS (on linear tyres, tyre_friction 0, it
        changes nothing, as tyre_shape)."""
        ratio, (low, high) = self.p["tyre_friction_ratio"], FRICTION_RATIO_BOUNDS
        number = isinstance(ratio, (int, float)) and not isinstance(ratio, bool)
        self.require(number and low <= ratio <= high,
                     f"parameter tyre_friction_ratio={ratio!r}: expected a number in [{low:g}, {high:g}] (the rear "
                     f"tyres' peak friction over the front's, mu_r / mu_f; 1: one friction on both axles)")

    def _parameters(self) -> TractorParameters:
        try:
            return TractorParameters.of(self.p)
        except ValueError as exc:
            raise ComponentError(f"{self.name}: {exc}") from None

    def initialize(self, t0: float, dt: float) -> None:
        p = self.p
        self.require(p["model"] in MODELS, f"parameter model={p['model']!r}; expected one of {MODELS}")
        self.params = self._parameters()
        for key in ("m", "I", "l_f", "l_r", "C_f", "C_r", "sigma_f", "sigma_r"):
            self.require(getattr(self.params, key) > 0, f"parameter {key} must be > 0, got {getattr(self.params, key)}")
        self.require(float(p["min_speed"]) > 0, f"parameter min_speed must be > 0, got {p['min_speed']}")
        self._tf = None
        self._slope = float(p["slope_angle"]) != 0.0 or bool(p["terrain_file"])
        self._cornering = float(p["cornering_speed_slope"]) != 0.0
        self._saturation = float(p["tyre_friction"]) > 0.0
        self.require(p["model"] != "transfer_function" or not (self._slope or self._cornering or self._saturation),
                     "slope_angle, terrain_file, cornering_speed_slope and tyre_friction need a physical model "
                     "(bicycle, rlf, rlfr)")
        self.require(not self._saturation or 0.0 < float(p["tyre_shape"]) < 2.0,
                     f"parameter tyre_shape={p['tyre_shape']}: expected 0 < C < 2")
        try:
            self._ground = ground_of(p["slope_angle"], p["slope_downhill_heading"], p["terrain_file"])
        except ValueError as exc:
            self.require(False, f"parameter terrain_file: {exc}")
        self._pull = (0.0, 0.0)
        if p["model"] == "transfer_function":
            self._tf = controllable_canonical(p["tf_num"], p["tf_den"])
            n = self._tf[0].shape[0]
        else:
            n = state_space(p["model"], self.params, 1.0)[0].shape[0]
        self._min_speed, self._cache_res = float(p["min_speed"]), float(p["speed_cache_resolution"])
        self.z = [0.0] * n
        self.x, self.y_pos, self.psi = float(p["x0"]), float(p["y0"]), float(p["psi0"])
        self._cache: dict[tuple[int, float], tuple[np.ndarray, np.ndarray, np.ndarray, list]] = {}
        self._update_ground()
        self._lever = (p["antenna_forward"], p["antenna_left"], p["antenna_height"])
        self._arms = (self.params.l_r, self._lever[0], self._lever[1])     # the level step's lever arms
        self._offset = float(p["steer_angle_offset"])
        self.require(p["steering_geometry"] in STEERING_GEOMETRIES,
                     f"parameter steering_geometry={p['steering_geometry']!r}; expected one of {STEERING_GEOMETRIES}")
        self._geometry = p["steering_geometry"]
        # level ground with linear tyres: the step of ``_level_step`` (pull, roll and pitch stay as set here)
        self._level = not (self._slope or self._saturation)
        self._affine = _AFFINE.get(n, _affine_held)
        self._held, self._product = np.zeros(n), np.zeros(n)    # the level step's state as an array, Ad z
        self._held_of = self.z                                  # the state ``_held`` holds
        self._views()
        self._set_outputs(0.0, 0.0, 0.0)

    def _views(self) -> None:
        """``_held`` and ``_product`` written and read through memoryviews: a float in or out without
        numpy's item dispatch."""
        self._held_view, self._product_view = memoryview(self._held), memoryview(self._product)

    def __getstate__(self) -> dict:
        """Pickled (and copied) without the memoryviews, which are not picklable."""
        return {k: v for k, v in self.__dict__.items() if k not in ("_held_view", "_product_view")}

    def __setstate__(self, state: dict) -> None:
        """Unpickled or copied: arrays of its own (a copy stepping must not write the original's
        state) and their memoryviews."""
        self.__dict__.update(state)
        if "_held" in state:
            self._held, self._product = np.array(self._held), np.array(self._product)
            self._views()

    def _update_ground(self) -> None:
        """Gradient, pull and attitude of the ground at the CG."""
        gx, gy = self._ground.gradient(self.x, self.y_pos)
        self._pull = slope_pull(gx, gy)
        self._attitude = attitude(gx, gy, self.psi)

    def discretized(self, v: float, dt: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, list]:
        """(Ad, Bd, C, Bd's entries as floats) at speed v (cached on a grid of speed_cache_resolution)."""
        key = (int(round(v / self._cache_res)), dt)
        hit = self._cache.get(key)
        if hit is None:
            vq = key[0] * self._cache_res
            if self._tf is not None:
                A, B, C = self._tf
            else:
                params = self.params
                if self._cornering:
                    params = with_cornering_scale(params, cornering_scale(
                        vq, self.p["cornering_speed_slope"], self.p["cornering_reference_speed"]))
                A, B, C = state_space(self.p["model"], params, vq)
                if self._slope:
                    B = np.column_stack([B, lateral_disturbance_column(A.shape[0])])
            Ad, Bd = zoh_discretize(A, B, dt)
            hit = self._cache[key] = (Ad, Bd, C, Bd.tolist())
            if len(self._cache) > 20000:
                self._cache.clear()
        return hit

    def _yaw_rate_and_lateral(self) -> tuple[float, float]:
        """(gamma, v_y) of the current dynamic state, before low-speed scaling (C does not depend
        on the speed: the physical models' state is [v_y, gamma, ...])."""
        if self._tf is None:
            return float(self.z[1]), float(self.z[0])
        gamma = float(self._tf[2] @ self.z)
        return gamma, self.params.l_r * gamma

    def _set_outputs(self, v: float, gamma: float, v_y: float) -> None:
        lr = self.params.l_r
        c, s = math.cos(self.psi), math.sin(self.psi)
        y = self.y
        y["yaw_rate"], y["lateral_velocity"], y["heading"] = gamma, v_y, self.psi
        y["x_cg"], y["y_cg"] = self.x, self.y_pos
        y["x_rear"], y["y_rear"] = self.x - lr * c, self.y_pos - lr * s
        v_lat_rear = v_y - lr * gamma
        y["vel_east_rear"] = v * c - v_lat_rear * s
        y["vel_north_rear"] = v * s + v_lat_rear * c
        roll, pitch = self._attitude
        if roll == 0.0 and pitch == 0.0:    # level: lever_offset's sums with cos 0 = 1, sin 0 = 0, to the bit
            forward, left = self._lever[0], self._lever[1]
            dx, dy = c * forward - s * left, s * forward + c * left
        else:
            dx, dy = lever_offset(roll, pitch, self.psi, *self._lever)
        y["x_antenna"], y["y_antenna"] = y["x_rear"] + dx, y["y_rear"] + dy
        y["vel_east_antenna"] = y["vel_east_rear"] - gamma * dy
        y["vel_north_antenna"] = y["vel_north_rear"] + gamma * dx
        y["slope_pull_east"], y["slope_pull_north"] = self._pull
        y["roll"], y["pitch"] = roll, pitch

    def _saturated_step(self, v: float, delta: float, dt: float) -> np.ndarray:
        """The state after dt with Magic Formula tyres (models.tyre.ros2_step, sub-steps <= 2 ms)."""
        scale = cornering_scale(v, self.p["cornering_speed_slope"], self.p["cornering_reference_speed"]) \
            if self._cornering else 1.0
        mu = float(self.p["tyre_friction"])
        tyre = {"mu": mu, "mu_r": mu * float(self.p["tyre_friction_ratio"]), "shape": float(self.p["tyre_shape"]),
                "C_f": self.params.C_f * scale, "C_r": self.params.C_r * scale}
        n = max(1, int(math.ceil(dt / 0.002)))
        z = np.asarray(self.z, dtype=float)          # initialize leaves a list of floats for the level step
        for _ in range(n):
            z = ros2_step(self.p["model"], self.params, z, dt / n, v, v, delta, delta, **tyre)
        return z

    def _level_step(self, v: float, delta: float, dt: float) -> None:
        """``step`` on level ground with linear tyres: z <- Ad(v) z + Bd(v) delta on a state of
        Python floats (the product by Ad.dot into arrays held from initialize, matmul's sums without
        its dispatch; the sum element by element, as numpy's), the same to the bit; then ``_move``
        and ``_set_outputs`` written out with zero roll, pitch and pull (set at initialize)."""
        speed = abs(v)
        vmin = self._min_speed
        v_eff, scale = (speed, 1.0) if speed >= vmin else (vmin, speed / vmin)
        # discretized's key, inline (round of a float is the int the key holds)
        hit = self._cache.get((round(v_eff / self._cache_res), dt))
        Ad, _, _, bd = hit if hit is not None else self.discretized(v_eff, dt)
        z0, held = self.z, self._held
        if z0 is not self._held_of:            # a state set from outside: the array follows it
            held[:] = z0
            z0 = held.tolist()
        if self._tf is None:                    # (v_y, gamma, ...)
            Ad.dot(held, self._product)
            z = self.z = self._held_of = self._affine(self._product_view.tolist(), bd, delta, self._held_view)
            vy0, gamma0, vy1, gamma1 = z0[0], z0[1], z[0], z[1]
        else:
            gamma0, vy0 = self._yaw_rate_and_lateral()
            Ad.dot(held, self._product)
            self.z = self._held_of = self._affine(self._product_view.tolist(), bd, delta, self._held_view)
            gamma1, vy1 = self._yaw_rate_and_lateral()
        if scale != 1.0:
            gamma0, vy0, gamma1, vy1 = scale * gamma0, scale * vy0, scale * gamma1, scale * vy1
        psi = self.psi                                              # _move
        psi_mid = psi + 0.25 * dt * (gamma0 + gamma1)
        vy_mid = 0.5 * (vy0 + vy1)
        c, s = math.cos(psi_mid), math.sin(psi_mid)
        self.x = x = self.x + dt * (v * c - vy_mid * s)
        self.y_pos = y_pos = self.y_pos + dt * (v * s + vy_mid * c)
        self.psi = psi = psi + 0.5 * dt * (gamma0 + gamma1)
        lr, forward, left = self._arms                              # _set_outputs(v, gamma1, vy1)
        c, s = math.cos(psi), math.sin(psi)
        y = self.y
        y["yaw_rate"], y["lateral_velocity"], y["heading"] = gamma1, vy1, psi
        y["x_cg"], y["y_cg"] = x, y_pos
        y["x_rear"], y["y_rear"] = x_rear, y_rear = x - lr * c, y_pos - lr * s
        v_lat_rear = vy1 - lr * gamma1
        y["vel_east_rear"] = ve = v * c - v_lat_rear * s
        y["vel_north_rear"] = vn = v * s + v_lat_rear * c
        dx, dy = c * forward - s * left, s * forward + c * left
        y["x_antenna"], y["y_antenna"] = x_rear + dx, y_rear + dy
        y["vel_east_antenna"] = ve - gamma1 * dy
        y["vel_north_antenna"] = vn + gamma1 * dx

    def _move(self, v: float, dt: float, gamma0: float, vy0: float, gamma1: float, vy1: float) -> None:
        """The pose by the midpoint rule over the step (yaw rate and lateral velocity from gamma0,
        vy0 to gamma1, vy1), the ground under it and the outputs."""
        psi = self.psi
        psi_mid = psi + 0.25 * dt * (gamma0 + gamma1)
        vy_mid = 0.5 * (vy0 + vy1)
        c, s = math.cos(psi_mid), math.sin(psi_mid)
        self.x += dt * (v * c - vy_mid * s)
        self.y_pos += dt * (v * s + vy_mid * c)
        self.psi = psi + 0.5 * dt * (gamma0 + gamma1)
        if self._slope:                      # level ground: no pull, zero roll and pitch at every pose
            self._update_ground()
        self._set_outputs(v, gamma1, vy1)

    def step(self, t: float, dt: float) -> None:
        v = float(self.u["speed"])
        delta = steer_input(float(self.u["steer_angle"]) + self._offset, self._geometry)
        if self._level:
            self._level_step(v, delta, dt)
            return
        vmin, speed = self._min_speed, abs(v)
        v_eff, scale = (speed, 1.0) if speed >= vmin else (vmin, speed / vmin)
        gamma0, vy0 = self._yaw_rate_and_lateral()
        if self._saturation:
            z = self._saturated_step(v_eff, delta, dt)
        else:
            hit = self._cache.get((int(round(v_eff / self._cache_res)), dt))       # discretized's, inline
            Ad, Bd, _, _ = hit if hit is not None else self.discretized(v_eff, dt)
            z = Ad @ self.z
        a_lat = -self._pull[0] * math.sin(self.psi) + self._pull[1] * math.cos(self.psi) if self._slope else 0.0
        if self._saturation:
            z[0] += dt * a_lat
        elif self._slope:
            z += Bd[:, 0] * delta + Bd[:, 1] * a_lat
        else:
            z += Bd * delta
        self.z = z
        gamma1, vy1 = self._yaw_rate_and_lateral()
        self._move(v, dt, scale * gamma0, scale * vy0, scale * gamma1, scale * vy1)

    def linear_model(self, step: float, speed: float) -> Block:
        """Yaw dynamics at v (models.yaw_dynamics; v_y = l_r gamma for a transfer-function model)
        with the pose on the straight: psi' = gamma, y_cg' = v psi + v_y; R = CG - l_r psi, the
        antenna a lever arm f ahead of R: y_ant = y_R + f psi, its velocity + f gamma.

        On a plane (``slope_angle``) the deviations are about the steady state that holds the line
        against the pull (plant_ground); the pull across the heading turns with it, dv_y/dt gains
        (d a_lat / d psi) psi, roll and pitch follow the heading (d roll / d psi psi, ...), and the antenna's
        lever, leaning with them, moves by (d lever / d psi) psi east and north; the line runs along the
        velocity, the body turned by the crab angle psi_0 = -v_y0 / v off it, so a change of the crab
        moves R along the line, x' = (v_y0 / v) v_y (outputs x_antenna, roll and pitch, the lateral
        channel's share of them, only on a plane). The crab angle (0.5 deg on 10 deg) is left out elsewhere."""
        p = self.p
        Ay, By, Cy, vy, params = _yaw_dynamics(self, speed)
        ground = self.linear_ground(speed)
        tilted = ground is not None
        slope = _per_heading(p) if tilted else {"lever_north": float(p["antenna_forward"])}
        n = len(By)
        m = n + 3 if tilted else n + 2                   # on a plane also x: the crab's share of the along-track motion
        A = np.zeros((m, m))
        A[:n, :n] = Ay
        A[n, :n] = Cy                                    # psi' = gamma
        A[n + 1, :n], A[n + 1, n] = vy, speed            # y' = v psi + v_y
        if tilted:
            A[:n, n] += lateral_disturbance_column(n) * slope["pull"]      # the pull turning with psi
            A[n + 2, :n] = vy * ground.crab / speed      # x' = v cos psi - v_y sin psi, sin psi_0 = -v_y0 / v
        B = np.concatenate([By, np.zeros(m - n)]).reshape(-1, 1)
        e = np.eye(m)
        gamma, psi, y, lr = np.concatenate([Cy, np.zeros(m - n)]), e[n], e[n + 1], params.l_r
        f = slope["lever_north"]
        turning = _on_the_plane(p, 0.0)["lever_east"] if tilted else f     # the plant's antenna velocity: the lever
        lateral = np.concatenate([vy, np.zeros(m - n)])                   # turned by gamma, its lean held
        vel_rear = speed * psi + lateral - lr * gamma
        rows = {"yaw_rate": gamma, "lateral_velocity": lateral, "heading": psi, "y_cg": y, "y_rear": y - lr * psi,
                "vel_north_rear": vel_rear, "y_antenna": y - lr * psi + f * psi,
                "vel_north_antenna": vel_rear + turning * gamma}
        if tilted:                                       # the lateral channel's share of these: nil on level ground
            rows |= {"x_antenna": e[n + 2] + slope["lever_east"] * psi, "roll": slope["roll"] * psi,
                     "pitch": slope["pitch"] * psi}
        Ad, Bd = zoh_discretize(A, B, step)
        return Block.of(self.name, ["steer_angle"], list(rows), Ad, Bd, np.array(list(rows.values())), sampled=False)

    def linear_ground(self, speed: float) -> Ground | None:
        """The ground under the yaw plant ``self`` driving straight east at ``speed`` on its plane
        (``slope_angle``, ``slope_downhill_heading``), None on level ground: roll, pitch and the pull across
        the heading a_lat and their change with psi (models.terrain), the left specific force the IMU reads
        there, f_y = g sin(roll) cos(pitch) (models.terrain.body_of with no acceleration), and the rear
        axle's crab: the yaw dynamics' steady state holding the line against the pull, gamma = 0,

            A z + B delta + E a_lat = 0,   C z = 0        (n + 1 equations in z, delta)

        whose v_y (state 0) is R's sideways velocity (gamma = 0: every point of the body moves alike).
        A height grid (``terrain_file``) is not linearised here: None (the caller says so)."""
        p = self.p
        if not float(p.get("slope_angle", 0.0) or 0.0) or p.get("terrain_file") or p.get("model") == "transfer_function":
            return None
        here, slope = _on_the_plane(p, 0.0), _per_heading(p)
        A, B, C, _, _ = _yaw_dynamics(self, speed)
        n = len(B)
        M = np.zeros((n + 1, n + 1))
        M[:n, :n], M[:n, n], M[n, :n] = A, B, C
        rhs = np.concatenate([-lateral_disturbance_column(n) * here["pull"], [0.0]])
        z = np.linalg.solve(M, rhs)
        return Ground(roll=here["roll"], pitch=here["pitch"], roll_per_heading=slope["roll"],
                      pitch_per_heading=slope["pitch"], pull=here["pull"], pull_per_heading=slope["pull"],
                      specific_force=GRAVITY * math.sin(here["roll"]) * math.cos(here["pitch"]), crab=float(z[0]))


COMPONENT = TractorYawPlant
