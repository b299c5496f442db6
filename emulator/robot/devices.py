"""The virtual robot's devices: what each sends and accepts, and the motion they all observe.

Wire protocol (every device, TCP): one JSON object per line (UTF-8, ``\\n``-terminated, at most
64 KiB) each way. A working device sends a data frame every ``1/rate_hz`` s to every connected
client; a client may send commands. Every frame has ``seq`` (per device, from 0 at power-on)
and ``t_ms`` (the emulator's clock). Angles are radians, rates rad/s, lengths m unless the key
says ``_mm``::

    base      -> {"seq", "t_ms", "x", "y", "yaw", "speed", "yaw_rate"}        (wheel odometry)
              <- {"cmd": "velocity", "linear": m/s, "angular": rad/s}       (held 0.5 s)
    lidar     -> {"seq", "t_ms", "angle_min", "angle_increment", "range_max_mm",
                  "ranges_mm": [1081 ints]}                                 (UTM-30LX geometry)
    servo     -> {"seq", "t_ms", "roll", "pitch", "target_roll", "target_pitch"}
              <- {"cmd": "angle", "roll": rad, "pitch": rad}                (clamped to +-0.5)
    imu       -> {"seq", "t_ms", "roll", "pitch", "yaw", "yaw_rate", "acc": [x, y, z]}
    joystick  -> {"seq", "t_ms", "axes": [turn, forward], "buttons": [0, 0]}
    camera    -> {"seq", "t_ms", "width", "height", "min_c", "max_c"}          (a thermal image's
                                                                             size and range)

A bad command line gets ``{"error": "..."}`` back and changes nothing; a device that is booting
or hung ignores commands silently (it is not listening). Power, boot and hang are not decided
here (``emulator.robot.server`` reads them from the electronics); these classes only turn the
clock and the commands into frames.

All devices share one ``RobotWorld``: the robot body's pose and velocity. The base drives it (its
velocity follows the last command with a 0.2 s lag, and stops without a command for 0.5 s or
while the base is not working); the base's odometry and the IMU both measure its yaw rate,
each with its own noise, so their trends match (``related: [odom_yaw_rate, imu_yaw_rate]``).
"""

from __future__ import annotations

import math
import random
from typing import Any

from emulator.robot.config import DeviceSpec

COMMAND_HOLD_MS = 500  # the base stops when commands stop (the controller's watchdog)
LAG_S = 0.2  # first-order lag of the base's velocity
MAX_LINEAR = 1.5  # m/s, about the Jaguar's top speed
MAX_ANGULAR = 2.0  # rad/s
SERVO_LIMIT = 0.5  # rad
SERVO_SPEED = 1.0  # rad/s

# Hokuyo UTM-30LX: 270 deg in 0.25 deg steps, 0.1-30 m
LIDAR_STEPS = 1081
LIDAR_INCREMENT = math.radians(0.25)
LIDAR_ANGLE_MIN = -math.radians(135.0)
LIDAR_RANGE_MAX_MM = 30000
ROOM = (8.0, 5.0)  # a rectangular room, m; the robot near its middle


def _number(msg: dict[str, Any], key: str) -> float:
    value = msg.get(key)
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise ValueError(f"{key} must be a number, not {value!r}")
    return float(value)


def _clamp(x: float, limit: float) -> float:
    return max(-limit, min(limit, x))


class RobotWorld:
    """The robot body: pose and velocity, integrated on the emulator's clock."""

    def __init__(self) -> None:
        self.t_ms = 0
        self.x = self.y = self.yaw = 0.0
        self.speed = self.yaw_rate = 0.0
        self.cmd = (0.0, 0.0)
        self.cmd_ms = -COMMAND_HOLD_MS
        self.drive_ok = False  # the base works: its motors follow commands

    def command(self, linear: float, angular: float, now_ms: int) -> None:
        self.advance(now_ms)
        self.cmd = (_clamp(linear, MAX_LINEAR), _clamp(angular, MAX_ANGULAR))
        self.cmd_ms = now_ms

    def advance(self, now_ms: int) -> None:
        while self.t_ms < now_ms:
            step = min(10, now_ms - self.t_ms)
            dt = step / 1000.0
            held = self.drive_ok and self.t_ms - self.cmd_ms < COMMAND_HOLD_MS
            v, w = self.cmd if held else (0.0, 0.0)
            k = min(1.0, dt / LAG_S)
            self.speed += (v - self.speed) * k
            self.yaw_rate += (w - self.yaw_rate) * k
            self.yaw = math.remainder(self.yaw + self.yaw_rate * dt, math.tau)
            self.x += self.speed * math.cos(self.yaw) * dt
            self.y += self.speed * math.sin(self.yaw) * dt
            self.t_ms += step


class SimDevice:
    """One device's frames and commands; ``rng`` gives its measurement noise."""

    def __init__(self, spec: DeviceSpec, world: RobotWorld, rng: random.Random) -> None:
        self.spec = spec
        self.world = world
        self.rng = rng
        self.seq = 0

    def reset(self, now_ms: int) -> None:
        """Power-on: counters and internal state start again."""
        self.seq = 0

    def working(self, ok: bool, now_ms: int) -> None:
        """Told when the device starts or stops working (powered, booted, not hung)."""

    def frame(self, now_ms: int) -> dict[str, Any]:
        self.world.advance(now_ms)
        out: dict[str, Any] = {"seq": self.seq, "t_ms": now_ms, **self.data(now_ms)}
        self.seq += 1
        return out

    def data(self, now_ms: int) -> dict[str, Any]:
        return {}

    def command(self, msg: dict[str, Any], now_ms: int) -> None:
        """Apply one command; ``ValueError`` with a message for the client if it is bad."""
        raise ValueError(f"a {self.spec.kind} accepts no commands")


class Base(SimDevice):
    def working(self, ok: bool, now_ms: int) -> None:
        self.world.advance(now_ms)
        self.world.drive_ok = ok

    def data(self, now_ms: int) -> dict[str, Any]:
        w = self.world
        return {"x": round(w.x, 4), "y": round(w.y, 4), "yaw": round(w.yaw, 4),
                "speed": round(w.speed + self.rng.gauss(0, 0.005), 4),
                "yaw_rate": round(w.yaw_rate + self.rng.gauss(0, 0.01), 4)}

    def command(self, msg: dict[str, Any], now_ms: int) -> None:
        if msg.get("cmd") != "velocity":
            raise ValueError('the base accepts {"cmd": "velocity", "linear": .., "angular": ..}')
        self.world.command(_number(msg, "linear"), _number(msg, "angular"), now_ms)


def _room_profile() -> list[int]:
    """Ranges (mm) all around, in lidar steps, from the room's middle (index 0 = yaw 0)."""
    half_x, half_y = ROOM[0] / 2, ROOM[1] / 2
    n = round(math.tau / LIDAR_INCREMENT)
    out = []
    for i in range(n):
        a = i * LIDAR_INCREMENT
        c, s = math.cos(a), math.sin(a)
        d = min(half_x / abs(c) if abs(c) > 1e-9 else math.inf,
                half_y / abs(s) if abs(s) > 1e-9 else math.inf)
        out.append(min(LIDAR_RANGE_MAX_MM, round(d * 1000)))
    return out


class Lidar(SimDevice):
    def __init__(self, spec: DeviceSpec, world: RobotWorld, rng: random.Random) -> None:
        super().__init__(spec, world, rng)
        self.profile = _room_profile()
        self.noise = [round(rng.gauss(0, 10)) for _ in range(997)]  # prime: no visible pattern

    def data(self, now_ms: int) -> dict[str, Any]:
        n = len(self.profile)
        # the world turns the other way in the scanner's frame
        first = round((LIDAR_ANGLE_MIN - self.world.yaw) / LIDAR_INCREMENT)
        k = self.seq * 31
        ranges = [self.profile[(first + i) % n] + self.noise[(k + i) % 997]
                  for i in range(LIDAR_STEPS)]
        return {"angle_min": round(LIDAR_ANGLE_MIN, 6),
                "angle_increment": round(LIDAR_INCREMENT, 8),
                "range_max_mm": LIDAR_RANGE_MAX_MM, "ranges_mm": ranges}


class Servo(SimDevice):
    def __init__(self, spec: DeviceSpec, world: RobotWorld, rng: random.Random) -> None:
        super().__init__(spec, world, rng)
        self.angles = [0.0, 0.0]
        self.target = [0.0, 0.0]
        self.t_ms = 0
        self.cmd_ms = -COMMAND_HOLD_MS  # the last command (the world's leveling checks it)

    def reset(self, now_ms: int) -> None:
        super().reset(now_ms)
        self.target = [0.0, 0.0]
        self.t_ms = now_ms

    def _move(self, now_ms: int) -> None:
        step = SERVO_SPEED * max(0, now_ms - self.t_ms) / 1000.0
        self.t_ms = now_ms
        for i in (0, 1):
            self.angles[i] += _clamp(self.target[i] - self.angles[i], step)

    def data(self, now_ms: int) -> dict[str, Any]:
        self._move(now_ms)
        return {"roll": round(self.angles[0], 4), "pitch": round(self.angles[1], 4),
                "target_roll": round(self.target[0], 4),
                "target_pitch": round(self.target[1], 4)}

    def command(self, msg: dict[str, Any], now_ms: int) -> None:
        if msg.get("cmd") != "angle":
            raise ValueError('the servo accepts {"cmd": "angle", "roll": .., "pitch": ..}')
        roll, pitch = _number(msg, "roll"), _number(msg, "pitch")
        self._move(now_ms)
        self.target = [_clamp(roll, SERVO_LIMIT), _clamp(pitch, SERVO_LIMIT)]
        self.cmd_ms = now_ms


class Imu(SimDevice):
    def data(self, now_ms: int) -> dict[str, Any]:
        w, t = self.world, now_ms / 1000.0
        # rubble: the body rolls and pitches a little, more when it moves
        bump = 0.02 + 0.05 * min(1.0, abs(w.speed))
        roll = bump * math.sin(t / 1.3)
        pitch = bump * math.sin(t / 2.1 + 1.0)
        g = 9.81
        return {"roll": round(roll + self.rng.gauss(0, 0.002), 4),
                "pitch": round(pitch + self.rng.gauss(0, 0.002), 4),
                "yaw": round(w.yaw, 4),
                "yaw_rate": round(w.yaw_rate + self.rng.gauss(0, 0.005), 4),
                "acc": [round(-g * math.sin(pitch), 3), round(g * math.sin(roll), 3),
                        round(g * math.cos(roll) * math.cos(pitch), 3)]}


class Joystick(SimDevice):
    """An operator driving a slow slalom: forward and back, turning left and right."""

    def data(self, now_ms: int) -> dict[str, Any]:
        t = now_ms / 1000.0
        turn = 0.6 * math.sin(math.tau * t / 6.0)
        forward = 0.4 * math.sin(math.tau * t / 20.0)
        return {"axes": [round(turn, 3), round(forward, 3)], "buttons": [0, 0]}


class Camera(SimDevice):
    """A thermal camera (FLIR PathFindIR class, 160x120): the image's temperature range; what
    it shows of the arena is the world's business (``emulator.robot.world``)."""

    def data(self, now_ms: int) -> dict[str, Any]:
        return {"width": 160, "height": 120,
                "min_c": round(18.0 + self.rng.gauss(0, 0.3), 2),
                "max_c": round(24.0 + self.rng.gauss(0, 0.3), 2)}


CLASSES: dict[str, type[SimDevice]] = {
    "base": Base, "lidar": Lidar, "servo": Servo, "imu": Imu, "joystick": Joystick,
    "camera": Camera,
}


def make(spec: DeviceSpec, world: RobotWorld, rng: random.Random) -> SimDevice:
    return CLASSES[spec.kind](spec, world, rng)
