"""A hand turn between two static poses, as the test generators make it (peer_imu_tk.simulate and
sim_effects.py, neither using calbench's code): a rotation by theta (rad) about a fixed body axis
over T seconds with the rate profile theta/T·(1 − cos 2πτ/T), sampled at `rate` Hz."""
import math


def rotation(axis, ang):
    """The rotation matrix of angle ang about the unit vector axis (Rodrigues)."""
    x, y, z = axis
    c, s = math.cos(ang), math.sin(ang)
    return [[c + x * x * (1 - c), x * y * (1 - c) - z * s, x * z * (1 - c) + y * s],
            [y * x * (1 - c) + z * s, c + y * y * (1 - c), y * z * (1 - c) - x * s],
            [z * x * (1 - c) - y * s, z * y * (1 - c) + x * s, c + z * z * (1 - c)]]


def turn_samples(theta, T, rate):
    """Per sample of the turn: (rate about the axis at the sample, rad/s; angle turned since the
    previous sample, rad) — the exact integral of the profile, so the turn ends at theta."""
    dt = 1 / rate
    for k in range(1, int(T * rate) + 1):
        tau = k * dt
        r = theta / T * (1 - math.cos(2 * math.pi * tau / T))
        a1 = theta * (tau / T - math.sin(2 * math.pi * tau / T) / (2 * math.pi))
        a0 = theta * ((tau - dt) / T - math.sin(2 * math.pi * (tau - dt) / T) / (2 * math.pi))
        yield r, a1 - a0
