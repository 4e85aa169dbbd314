"""IMU on the tractor (typically 100 Hz): roll and pitch from the unit's attitude filter, the yaw
gyro and the three accelerometers, each with bias and noise (grades: models.sensor_grades).

Truth from the plant: roll phi, pitch theta (models.terrain conventions), heading psi, the heading
rate dpsi/dt and the horizontal velocity of the mounting point. With R = Rz(psi) Ry(-theta) Rx(phi):

    gyro z  = (R^T (0, 0, dpsi/dt))_z + b_g + n_g = cos(phi) cos(theta) dpsi/dt + b_g + n_g
    f       = R^T (a_east, a_north, g) + b_a + n_a        (specific force, body forward/left/up)
    roll    = phi + b_phi + n_phi,  pitch = theta + b_theta + n_theta

a = the velocity's difference over one sample (the first sample: 0); the roll and pitch rates
are left out of the gyro (they change only as the heading turns on a plane). b_g = turn-on bias
(drawn once) + a first-order Gauss-Markov in-run bias; the white noises have std sqrt(PSD /
T_s); the attitude offsets b_phi, b_theta are drawn once per run.
"""
from __future__ import annotations

import math

from agrobot.orchestrator.component import Component, inp, out, par

from .models import sensor_grades as grade
from .models.terrain import GRAVITY, body_of
from .models.loop_blocks import Block, Ground, LEVEL


class IMUSensor(Component):
    sampled = True
    roles = ("imu",)
    variables = (
        inp("roll", "rad", 0.0, "true roll (left side up positive)"),
        inp("pitch", "rad", 0.0, "true pitch (nose up positive)"),
        inp("heading", "rad", 0.0, "true heading psi"),
        inp("yaw_rate", "rad/s", 0.0, "true heading rate dpsi/dt"),
        inp("vel_east", "m/s", 0.0, "true east velocity of the mounting point"),
        inp("vel_north", "m/s", 0.0, "true north velocity of the mounting point"),
        par("gyro_noise_psd", "rad2/s", grade.GYRO_NOISE_DENSITY ** 2, "rate noise: the square of the noise density "
            "(the angle random walk)"),
        par("gyro_bias_std", "rad/s", grade.GYRO_TURN_ON_BIAS, "turn-on bias, 1 sigma (drawn once)"),
        par("gyro_bias_instability", "rad/s", grade.GYRO_BIAS_INSTABILITY, "in-run bias: Gauss-Markov std"),
        par("gyro_bias_time_constant", "s", grade.GYRO_BIAS_TIME_CONSTANT, "in-run bias: correlation time"),
        par("accel_noise_psd", "m2/s3", grade.ACCEL_NOISE_DENSITY ** 2, "accelerometer noise: the square of its "
            "noise density"),
        par("accel_bias_std", "m/s2", grade.ACCEL_TURN_ON_BIAS, "accelerometer turn-on bias, 1 sigma per axis"),
        par("attitude_bias_std", "rad", grade.ATTITUDE_BIAS, "roll and pitch offset, 1 sigma (drawn once)"),
        par("attitude_noise_std", "rad", grade.ATTITUDE_NOISE, "roll and pitch white noise per sample"),
        out("roll", "rad", 0.0, "measured roll"),
        out("pitch", "rad", 0.0, "measured pitch"),
        out("yaw_rate", "rad/s", 0.0, "gyro about the body's up axis"),
        out("accel_forward", "m/s2", 0.0, "specific force along the body's forward axis"),
        out("accel_left", "m/s2", 0.0, "specific force along the body's left axis"),
        out("accel_up", "m/s2", 9.81, "specific force along the body's up axis"),
    )
    feedthrough = {k: ("roll", "pitch", "heading", "yaw_rate", "vel_east", "vel_north")
                   for k in ("roll", "pitch", "yaw_rate", "accel_forward", "accel_left", "accel_up")}

    def initialize(self, t0: float, dt: float) -> None:
        p = self.p
        for key in ("gyro_noise_psd", "gyro_bias_std", "gyro_bias_instability", "accel_noise_psd",
                    "accel_bias_std", "attitude_bias_std", "attitude_noise_std"):
            self.require(p[key] >= 0, f"parameter {key} must be >= 0, got {p[key]}")
        self.require(p["gyro_bias_time_constant"] > 0, "parameter gyro_bias_time_constant must be > 0")
        rng = self.rng
        self.turn_on = float(rng.standard_normal() * p["gyro_bias_std"])
        self.in_run = float(rng.standard_normal() * p["gyro_bias_instability"])
        self.accel_bias = rng.standard_normal(3) * p["accel_bias_std"]
        self.attitude_bias = rng.standard_normal(2) * p["attitude_bias_std"]
        self.phi = math.exp(-dt / p["gyro_bias_time_constant"])
        self.gyro_std = math.sqrt(p["gyro_noise_psd"] / dt)
        self.accel_std = math.sqrt(p["accel_noise_psd"] / dt)
        self.previous_velocity: tuple[float, float] | None = None

    def step(self, t: float, dt: float) -> None:
        u, p, y = self.u, self.p, self.y
        w = self.rng.standard_normal(7)
        roll, pitch, psi = float(u["roll"]), float(u["pitch"]), float(u["heading"])
        velocity = (float(u["vel_east"]), float(u["vel_north"]))
        a = (0.0, 0.0) if self.previous_velocity is None else \
            ((velocity[0] - self.previous_velocity[0]) / dt, (velocity[1] - self.previous_velocity[1]) / dt)
        self.previous_velocity = velocity
        f = body_of(roll, pitch, psi, a[0], a[1], GRAVITY)
        b, n = self.accel_bias, self.accel_std
        y["accel_forward"], y["accel_left"], y["accel_up"] = (f[0] + b[0] + n * w[0], f[1] + b[1] + n * w[1],
                                                              f[2] + b[2] + n * w[2])
        y["yaw_rate"] = (math.cos(roll) * math.cos(pitch) * float(u["yaw_rate"]) + self.turn_on + self.in_run
                         + self.gyro_std * w[3])
        self.in_run = grade.gauss_markov_step(self.in_run, self.phi, p["gyro_bias_instability"], w[4])
        y["roll"] = roll + self.attitude_bias[0] + p["attitude_noise_std"] * w[5]
        y["pitch"] = pitch + self.attitude_bias[1] + p["attitude_noise_std"] * w[6]

    def linear_model(self, step: float, speed: float, ground: Ground = LEVEL) -> Block:
        """The IMU (components.imu_sensor) heading east without bias and noise, on the ground's roll phi
        and pitch theta: the gyro reads the heading rate about its up axis, cos(phi) cos(theta) gamma; roll
        and pitch read roll and pitch; the left specific force (models.terrain.body_of, the east
        acceleration 0 on the operating point) is the north acceleration by a difference over one sample
        and the gravity of the attitude,

            f_y = cos(phi) (v_n - v_n') / dt + g (cos(phi) cos(theta) d phi - sin(phi) sin(theta) d theta)

        (level ground: f_y = (v_n - v_n') / dt + g phi)."""
        cr, sr = math.cos(ground.roll), math.sin(ground.roll)
        cp, sp = math.cos(ground.pitch), math.sin(ground.pitch)
        return Block.of(self.name, ["yaw_rate", "vel_north", "roll", "pitch"], ["yaw_rate", "accel_left", "roll", "pitch"],
                        A=[[0.0]], B=[[0.0, 1.0, 0.0, 0.0]], C=[[0.0], [-cr / step], [0.0], [0.0]],
                        D=[[cr * cp, 0.0, 0.0, 0.0], [0.0, cr / step, GRAVITY * cr * cp, -GRAVITY * sr * sp],
                           [0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]])


COMPONENT = IMUSensor
