"""Synthetic systems for tests and benchmarks: random stable NARX models (MAKEMOD, §5.6.2) and
a closed-loop record of an open-loop unstable process (a ball on a beam)."""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np
from scipy import signal

from .budget import check_allocation, product
from .errors import IdentificationError, SimulationDivergedError
from .models import Narx
from .regression import regression_matrix

__all__ = ["BallAndBeam", "ball_and_beam", "band_limited_noise", "random_narx"]


def band_limited_noise(n_samples: int, n_channels: int = 1, *, cutoff: float = 0.25, seed=None):
    """Gaussian noise low-pass filtered at ``cutoff`` (fraction of Nyquist), unit RMS per channel.

    Channels are independent. ``seed`` is an int or a ``numpy.random.Generator``.

    Parameters
    ----------
    n_samples : int
        Number of samples.
    n_channels : int, optional
        Number of independent channels.
    cutoff : float, optional
        Low-pass cutoff as a fraction of the Nyquist frequency, in (0, 1).
    seed : int or numpy.random.Generator, optional
        Random seed or generator (default: fresh entropy).
    """
    if not 0 < cutoff < 1:
        raise IdentificationError(f"cutoff must be a fraction of Nyquist in (0, 1), got {cutoff!r}")
    for name, v, lo in (("n_samples", n_samples, 16), ("n_channels", n_channels, 1)):
        if not isinstance(v, (int, np.integer)) or isinstance(v, bool) or v < lo:
            raise IdentificationError(f"{name} must be an integer >= {lo}, got {v!r}")
    warm = 256
    check_allocation(
        product(n_samples + warm, n_channels, 8),
        f"band-limited noise of {n_samples:,} samples x {n_channels} channels x 8 bytes",
        "generate fewer samples or channels",
    )
    rng = np.random.default_rng(seed)
    e = rng.standard_normal((n_samples + warm, n_channels))
    sos = signal.butter(6, cutoff, output="sos")
    x = signal.sosfilt(sos, e, axis=0)[warm:]
    x -= x.mean(axis=0)
    return x / np.sqrt((x**2).mean(axis=0))


def _random_stable_filter(order: int, rng) -> tuple[np.ndarray, np.ndarray]:
    # poles inside a radius 0.5..0.9 circle (complex pairs), random numerator
    poles = []
    while len(poles) < order:
        r = rng.uniform(0.5, 0.9)
        if order - len(poles) >= 2:
            th = rng.uniform(0.1, 2.5)
            poles += [r * np.exp(1j * th), r * np.exp(-1j * th)]
        else:
            poles.append(r * rng.choice([-1.0, 1.0]))
    a = np.real(np.poly(poles)) if order else np.array([1.0])
    b = rng.standard_normal(order + 1)
    return b, a


def random_narx(
    ny: int,
    nu: int,
    order,
    degree,
    *,
    seed=None,
    n_samples: int = 4000,
    cutoff: float = 0.3,
    nonlinearity: float = 0.2,
    max_tries: int = 50,
) -> Narx:
    """A random, stable polynomial NARX model (the MAKEMOD generator of §5.6.2, refined).

    As in the reference text, a NARX model is identified between a random pseudo drive and a
    pseudo response. Here the pseudo response is a random stable linear filtering of the drive
    plus independent noise (so the model has a genuine input-output relation), the polynomial
    (degree >= 2) coefficients are scaled so that they contribute ``nonlinearity`` times the
    output RMS, and the model is accepted only if its free run on a fresh band-limited input
    stays within 10x the pseudo response's peak for several fresh inputs at 1.5-2x the
    nominal amplitude; otherwise the non-linear part is halved, or a
    new pseudo data set drawn.

    The model is meant to be driven by :func:`band_limited_noise` with the same ``cutoff`` and
    unit RMS per input channel.

    Parameters
    ----------
    ny, nu : int
        Numbers of outputs and inputs.
    order, degree : int or sequence of int
        Full-order model order and polynomial degree per output channel.
    seed : int or Generator, optional
        Random seed or generator (default: fresh entropy).
    n_samples : int
        Length of the pseudo data sets.
    cutoff : float
        Band limit of the pseudo drive, fraction of Nyquist.
    nonlinearity : float
        Target RMS of the polynomial part relative to the output RMS (0 = linear).
    max_tries : int
        Pseudo data sets drawn before giving up with :class:`IdentificationError`.
    """
    if ny < 1 or nu < 0:
        raise IdentificationError("need ny >= 1 and nu >= 0")
    if not 0 <= nonlinearity < 1:
        raise IdentificationError(f"nonlinearity must be in [0, 1), got {nonlinearity!r}")
    rng = np.random.default_rng(seed)
    orders = np.broadcast_to(np.asarray(order), (ny,))
    for _ in range(max_tries):
        u = band_limited_noise(n_samples, max(nu, 1), cutoff=cutoff, seed=rng)[:, :nu]
        y = np.zeros((n_samples, ny))
        for k in range(ny):
            for j in range(nu):
                b, a = _random_stable_filter(int(orders[k]), rng)
                y[:, k] += signal.lfilter(b, a, u[:, j])
            y[:, k] += 0.3 * band_limited_noise(n_samples, 1, cutoff=cutoff, seed=rng)[:, 0]
            y[:, k] /= np.sqrt((y[:, k] ** 2).mean())
        model = Narx(order, degree, bound_factor=10.0)
        model._fit_least_squares(u, y)  # no stability contract: its own check follows
        start = model.max_lag_
        coefs = []
        for k, ch in enumerate(model.channels_):
            c = model.coef_[k].copy()
            nl = np.count_nonzero(ch.terms, axis=1) >= 2
            if nl.any():
                X = regression_matrix(u, y, ch, start)
                part = X[:, nl] @ c[nl]
                rms = np.sqrt((part**2).mean())
                c[nl] *= nonlinearity / rms if rms > 0 else 0.0
            coefs.append(c)
        # stability check with margin: several fresh records at 1.5x the nominal amplitude
        checks = [
            margin * band_limited_noise(n_samples, max(nu, 1), cutoff=cutoff, seed=rng)[:, :nu]
            for margin in (1.5, 1.5, 1.5, 2.0)
        ]
        for _halving in range(12):
            model.coef_ = tuple(coefs)
            model._plan = None
            try:
                outs = [model.simulate(c) for c in checks]
                if all(np.all(np.sqrt((o**2).mean(axis=0)) > 1e-3) for o in outs):
                    return model
                break
            except SimulationDivergedError:
                for k, ch in enumerate(model.channels_):
                    nl = np.count_nonzero(ch.terms, axis=1) >= 2
                    coefs[k][nl] *= 0.5
    raise IdentificationError(
        f"could not generate a stable random NARX model in {max_tries} tries; "
        "lower the order, degree or nonlinearity"
    )


#: 5/7 g: a solid ball rolling without slipping on a tilted beam, m/s^2 per unit sin(angle)
_ROLLING_GAIN = 5.0 / 7.0 * 9.80665


@dataclass(frozen=True)
class BallAndBeam:
    """A ball-and-beam record taken in closed loop (an open-loop unstable, integrating process).

    A solid ball rolls on a beam whose angle ``alpha`` a servo sets; the ball's position ``x``
    obeys ``x'' = (5/7) g sin(alpha)`` (rolling without slip, the centripetal term neglected): a
    double integrator from the angle to the position, unstable in open loop. The servo follows
    its command with a first-order lag ``servo_lag``. A PD controller on the measured position
    keeps the ball on the beam: ``alpha_c = kp (r - x_m) - kd v_m + e``, with ``v_m`` the
    backward difference of the measured position, ``r`` a slow random set point and ``e`` a
    white excitation of the command. The record is what a lab would log: the measured beam angle
    (input) and the measured ball position (output), each with white sensor noise.

    Attributes
    ----------
    u : ndarray (N, 1)
        Measured beam angle, rad.
    y : ndarray (N, 1)
        Measured ball position, m.
    position : ndarray (N,)
        True ball position, m (no sensor noise).
    ts : float
        Sample interval, s.
    input_names : tuple of str
        The input's name and unit.
    output_names : tuple of str
        The output's name and unit.
    """

    u: np.ndarray
    y: np.ndarray
    position: np.ndarray
    ts: float
    input_names: tuple = ("beam angle [rad]",)
    output_names: tuple = ("ball position [m]",)

    @property
    def fs(self) -> float:
        """Sample rate, Hz."""
        return 1.0 / self.ts


@numba.njit(cache=True)
def _ball_and_beam_loop(r, e, n_angle, n_pos, ts, substeps, kp, kd, lag, gain):
    n = r.size
    alpha_m = np.empty(n)
    x_m = np.empty(n)
    x_true = np.empty(n)
    x, v, alpha = 0.0, 0.0, 0.0
    prev = 0.0
    h = ts / substeps
    for k in range(n):
        x_true[k] = x
        x_m[k] = x + n_pos[k]
        alpha_m[k] = alpha + n_angle[k]
        vel = (x_m[k] - prev) / ts if k > 0 else 0.0
        prev = x_m[k]
        command = kp * (r[k] - x_m[k]) - kd * vel + e[k]
        for _ in range(substeps):  # semi-implicit Euler on the held command
            alpha += h * (command - alpha) / lag
            v += h * gain * np.sin(alpha)
            x += h * v
    return alpha_m, x_m, x_true


def ball_and_beam(
    n_samples: int = 1000,
    *,
    seed=None,
    ts: float = 0.1,
    kp: float = 0.15,
    kd: float = 0.2,
    servo_lag: float = 0.05,
    set_point_rms: float = 0.15,
    excitation_rms: float = 0.02,
    angle_noise: float = 1e-3,
    position_noise: float = 1e-3,
) -> BallAndBeam:
    """A closed-loop record of a ball on a beam (see :class:`BallAndBeam`).

    The loop's characteristic equation (small angles, no servo lag) is
    ``s^2 + (5/7) g kd s + (5/7) g kp = 0``: with the defaults a natural frequency of
    1.0 rad/s and damping 0.68, stable in closed loop while the beam alone is a double
    integrator. Integrated with 20 substeps per sample (the command held over the sample).

    Parameters
    ----------
    n_samples : int
        Samples of the record.
    seed : int or numpy.random.Generator, optional
        Seed of the set point, the excitation and the sensor noise.
    ts : float
        Sample interval, s (0.1 s: 10 Hz).
    kp : float
        Proportional gain, rad per m of position error.
    kd : float
        Derivative gain, rad per m/s of measured velocity.
    servo_lag : float
        Time constant of the beam-angle servo, s.
    set_point_rms : float
        RMS of the random set point, m (band-limited noise, cut-off 0.05 of Nyquist).
    excitation_rms : float
        RMS of the white excitation added to the angle command, rad.
    angle_noise, position_noise : float
        RMS of the white sensor noise on the logged angle (rad) and position (m).
    """
    if (
        not isinstance(n_samples, (int, np.integer))
        or isinstance(n_samples, bool)
        or n_samples < 16
    ):
        raise IdentificationError(f"n_samples must be an integer >= 16, got {n_samples!r}")
    for name, v in (("ts", ts), ("servo_lag", servo_lag), ("kp", kp), ("kd", kd)):
        if not (isinstance(v, (int, float)) and v > 0 and np.isfinite(v)):
            raise IdentificationError(f"{name} must be a finite number > 0, got {v!r}")
    check_allocation(
        product(n_samples, 8, 8),
        f"a ball-and-beam record of {n_samples:,} samples",
        "fewer samples",
    )
    rng = np.random.default_rng(seed)
    r = set_point_rms * band_limited_noise(n_samples, 1, cutoff=0.05, seed=rng)[:, 0]
    e = excitation_rms * rng.standard_normal(n_samples)
    na = angle_noise * rng.standard_normal(n_samples)
    npos = position_noise * rng.standard_normal(n_samples)
    alpha, x_m, x = _ball_and_beam_loop(
        r, e, na, npos, float(ts), 20, float(kp), float(kd), float(servo_lag), _ROLLING_GAIN
    )
    if not np.all(np.isfinite(x_m)):
        raise IdentificationError("the closed loop diverged: raise kd or lower kp")
    return BallAndBeam(alpha[:, None], x_m[:, None], x, float(ts))
