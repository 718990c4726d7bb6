"""Transducers and data acquisition: from physics-rate sensor signals to sampled channels.

Every step is vectorised over the whole record (no loop per sample):

1. transducer dynamics: an accelerometer's high-pass (AC coupling, ``highpass_hz``), first order;
   the filters start in their steady state for the first value, as on a rig whose conditioning
   was powered before the test (no start-up transient from gravity or preload);
2. gain: the transducer's physical quantity per MuJoCo sensor unit (e.g. microstrain per metre of
   spring deflection);
3. additive noise (white at the physics rate, ``noise_rms`` in channel units after the
   anti-alias filter's band) and optional mains pickup (``mains_amplitude`` at ``mains_hz`` with
   a random phase per run) from the run's seeded generator;
4. anti-alias filter: causal Butterworth low-pass (``order`` at ``cutoff`` x fs) at the physics
   rate, as the analogue filter in front of an ADC;
5. sampling at the rig's fs (every ``decimation``-th physics sample, aligned with the drive);
6. optional quantisation to ``bits`` over ±full scale.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import signal

from ..errors import RigParameterError
from ._checks import check_number

__all__ = ["AntiAliasFilter", "Transducer", "acquire"]


@dataclass(frozen=True)
class Transducer:
    """One response transducer (the channel's conditioning chain)."""

    kind: str = "generic"  # accelerometer | load_cell | strain_gauge | lvdt | generic
    gain: float = 1.0  # channel unit per sensor unit
    noise_rms: float = 0.0  # channel units, RMS after the anti-alias filter
    highpass_hz: float = 0.0  # AC coupling corner (accelerometers); 0 = DC coupled
    mains_amplitude: float = 0.0  # mains pickup amplitude, channel units
    mains_hz: float = 50.0
    bits: int = 0  # ADC resolution over ±full scale; 0 = no quantisation

    def __post_init__(self):
        """Validate every field (a :class:`~vrig.errors.RigParameterError` names it)."""
        if not isinstance(self.kind, str):
            raise RigParameterError(
                f"transducer kind must be a string, got {self.kind!r}", "kind", self.kind, "a string"
            )
        check_number("gain", self.gain, nonzero=True)
        for key in ("noise_rms", "highpass_hz", "mains_amplitude"):
            check_number(key, getattr(self, key), minimum=0)
        check_number("mains_hz", self.mains_hz, exclusive_minimum=0)
        object.__setattr__(
            self, "bits", check_number("bits", self.bits, integer=True, minimum=0, maximum=32)
        )


@dataclass(frozen=True)
class AntiAliasFilter:
    """Causal Butterworth low-pass ahead of the ADC."""

    order: int = 6
    cutoff: float = 0.4  # fraction of the DAQ sample rate fs (0.4 fs: 80 % of Nyquist)

    def __post_init__(self):
        """Validate: ``order`` an integer in [1, 20], ``cutoff`` in (0, 0.5) of fs."""
        order = check_number("anti_alias.order", self.order, integer=True, minimum=1, maximum=20)
        object.__setattr__(self, "order", order)
        check_number("anti_alias.cutoff", self.cutoff, exclusive_minimum=0, exclusive_maximum=0.5)

    def sos(self, fs: float, physics_rate: float) -> np.ndarray:
        wn = self.cutoff * fs / (physics_rate / 2.0)
        if not 0 < wn < 1:
            raise ValueError(
                f"anti-alias cutoff {self.cutoff * fs} Hz is outside (0, {physics_rate / 2}) Hz"
            )
        return signal.butter(self.order, wn, output="sos")

    def response(self, f, fs: float, physics_rate: float) -> np.ndarray:
        """Complex frequency response at frequencies ``f`` [Hz] (for analytic models)."""
        _, h = signal.sosfreqz(
            self.sos(fs, physics_rate), worN=np.asarray(f, float), fs=physics_rate
        )
        return h


_MIN_HIGHPASS = 1e-12
"""High-pass corners below this fraction of the physics rate are DC coupling: their time constant
(> 1e11 physics steps) exceeds any record, and the filter's steady state is singular in floating
point (a corner of 1e-276 Hz made ``sosfilt_zi`` fail)."""


def _highpass_active(t: Transducer, physics_rate: float) -> bool:
    return t.highpass_hz > _MIN_HIGHPASS * physics_rate


def _highpass_sos(corner_hz: float, physics_rate: float) -> np.ndarray:
    return signal.butter(1, corner_hz, btype="highpass", fs=physics_rate, output="sos")


def transducer_response(t: Transducer, f, physics_rate: float) -> np.ndarray:
    """Complex response of the transducer's dynamics and gain at ``f`` [Hz]."""
    h = np.full(np.shape(f), t.gain, dtype=complex)
    if _highpass_active(t, physics_rate):
        _, hp = signal.sosfreqz(
            _highpass_sos(t.highpass_hz, physics_rate), worN=np.asarray(f, float), fs=physics_rate
        )
        h = h * hp
    return h


def acquire(
    raw: np.ndarray,
    transducers: list[Transducer],
    full_scale: np.ndarray,
    *,
    fs: float,
    decimation: int,
    aa: AntiAliasFilter,
    rng: np.random.Generator,
) -> tuple[np.ndarray, np.ndarray]:
    """Condition and sample physics-rate sensor signals ``raw`` (n_steps, n_channels).

    Returns ``(sampled, peak)``: the sampled channels (n_steps // decimation, n_channels) and
    each channel's peak magnitude before quantisation (for the transducer-range interlock).
    """
    physics_rate = fs * decimation
    n_steps, n = raw.shape
    x = np.empty_like(raw)
    for j, t in enumerate(transducers):
        col = raw[:, j] * t.gain
        if _highpass_active(t, physics_rate):  # started in its steady state (powered before)
            sos = _highpass_sos(t.highpass_hz, physics_rate)
            col, _ = signal.sosfilt(sos, col, zi=signal.sosfilt_zi(sos) * col[0])
        x[:, j] = col
    # noise: white at the physics rate, scaled so its RMS after the anti-alias filter is noise_rms
    rms = np.array([t.noise_rms for t in transducers])
    noise_gain = rms * np.sqrt(physics_rate / (2.0 * aa.cutoff * fs))
    x += rng.standard_normal((n_steps, n)) * noise_gain
    time = np.arange(n_steps) / physics_rate
    for j, t in enumerate(transducers):
        if t.mains_amplitude > 0:
            x[:, j] += t.mains_amplitude * np.sin(
                2 * np.pi * t.mains_hz * time + rng.uniform(0, 2 * np.pi)
            )
    sos = aa.sos(fs, physics_rate)
    zi = signal.sosfilt_zi(sos)[:, :, None] * x[0][None, None, :]
    x, _ = signal.sosfilt(sos, x, axis=0, zi=zi)
    sampled = x[::decimation].copy()
    peak = np.abs(sampled).max(axis=0)
    for j, t in enumerate(transducers):
        if t.bits:
            lsb = 2.0 * full_scale[j] / 2**t.bits
            sampled[:, j] = np.round(sampled[:, j] / lsb) * lsb
    return sampled, peak
