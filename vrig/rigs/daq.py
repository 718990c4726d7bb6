"""Transducers and data acquisition: from physics-rate sensor signals to sampled channels.

Every step is vectorised over the record, or over each chunk of it (:class:`Acquisition` carries
the filter states, the noise stream and the sampling phase across chunks; no loop per sample):

1. transducer dynamics: an accelerometer's high-pass (AC coupling, ``highpass_hz``), first order;
   the filters start in their steady state for the first value, as on a rig whose conditioning
   was powered before the test (no start-up transient from gravity or preload);
2. gain: the transducer's physical quantity per MuJoCo sensor unit (e.g. microstrain per metre of
   spring deflection);
3. additive noise (white at the physics rate, ``noise_rms`` in channel units after the
   anti-alias filter's band) and optional mains pickup (``mains_amplitude`` at ``mains_hz`` with
   a random phase per run, drawn before the noise) from the run's seeded DAQ generator;
4. anti-alias filter: causal Butterworth low-pass (``order`` at ``cutoff`` x fs) at the physics
   rate, as the analogue filter in front of an ADC;
5. sampling at the rig's fs (every ``decimation``-th physics sample, aligned with the drive);
6. optional quantisation to ``bits`` over ±full scale.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np
from scipy import signal

from ..errors import RigParameterError
from ._checks import check_number

__all__ = ["Acquisition", "AntiAliasFilter", "Transducer", "acquire"]


@dataclass(frozen=True)
class Transducer:
    """One response transducer (the channel's conditioning chain).

    Attributes
    ----------
    kind : {"accelerometer", "load_cell", "strain_gauge", "lvdt", "generic"}
        The kind of sensor.
    gain : float
        Channel unit per sensor unit.
    noise_rms : float
        Measurement noise, RMS after the anti-alias filter, in channel units.
    highpass_hz : float
        AC-coupling corner frequency in Hz (accelerometers); 0: DC coupled.
    mains_amplitude : float
        Mains pickup amplitude, in channel units.
    mains_hz : float
        Mains frequency in Hz.
    bits : int
        ADC resolution over ± full scale (0..32); 0: no quantisation.
    """

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
    """Causal Butterworth low-pass ahead of the ADC.

    Attributes
    ----------
    order : int
        Butterworth order.
    cutoff : float
        Corner frequency as a fraction of the DAQ sample rate fs (0.4 fs: 80 % of Nyquist).
    """

    order: int = 6
    cutoff: float = 0.4  # fraction of the DAQ sample rate fs (0.4 fs: 80 % of Nyquist)

    def __post_init__(self):
        """Validate: ``order`` an integer in [1, 20], ``cutoff`` in [0.05, 0.5) of fs (a DAQ's
        anti-alias filter sits near Nyquist; far below, the filter designed at the physics rate
        is numerically singular)."""
        order = check_number("anti_alias.order", self.order, integer=True, minimum=1, maximum=20)
        object.__setattr__(self, "order", order)
        check_number("anti_alias.cutoff", self.cutoff, minimum=0.05, exclusive_maximum=0.5)

    def sos(self, fs: float, physics_rate: float) -> np.ndarray:
        """Second-order sections of the filter, designed at the physics rate.

        Parameters
        ----------
        fs : float
            DAQ sample rate in Hz (sets the corner, ``cutoff * fs``).
        physics_rate : float
            Physics rate in Hz, at which the filter runs.

        Raises
        ------
        ValueError
            If the corner is not below the physics rate's Nyquist frequency.
        """
        wn = self.cutoff * fs / (physics_rate / 2.0)
        if not 0 < wn < 1:
            raise ValueError(
                f"anti-alias cutoff {self.cutoff * fs} Hz is outside (0, {physics_rate / 2}) Hz"
            )
        return _butter_sos(self.order, wn, "lowpass", None).copy()  # the cache's stays

    def response(self, f, fs: float, physics_rate: float) -> np.ndarray:
        """Complex frequency response at frequencies ``f`` [Hz] (for analytic models).

        Parameters
        ----------
        f : array_like
            Frequencies in Hz.
        fs : float
            DAQ sample rate in Hz.
        physics_rate : float
            Physics rate in Hz, at which the filter runs.
        """
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
    return _butter_sos(1, corner_hz, "highpass", physics_rate).copy()  # the cache's stays


@functools.lru_cache(maxsize=64)
def _butter_sos(order: int, wn: float, btype: str, fs: float | None) -> np.ndarray:
    """``scipy.signal.butter(order, wn, btype, fs=fs, output="sos")``, designed once per
    argument set (every run of a rig conditions its channels with the same filters); read-only
    (callers take copies)."""
    sos = signal.butter(order, wn, btype=btype, fs=fs, output="sos")
    sos.setflags(write=False)
    return sos


def transducer_response(t: Transducer, f, physics_rate: float) -> np.ndarray:
    """Complex response of the transducer's dynamics and gain at ``f`` [Hz].

    Parameters
    ----------
    t : Transducer
        The transducer.
    f : array_like
        Frequencies in Hz.
    physics_rate : float
        Physics rate in Hz, at which its high-pass runs.
    """
    h = np.full(np.shape(f), t.gain, dtype=complex)
    if _highpass_active(t, physics_rate):
        _, hp = signal.sosfreqz(
            _highpass_sos(t.highpass_hz, physics_rate), worN=np.asarray(f, float), fs=physics_rate
        )
        h = h * hp
    return h


class Acquisition:
    """The conditioning and sampling chain of one run, fed physics-rate sensor values chunk by
    chunk (:meth:`process`).

    Everything that carries from one physics step to the next carries across chunks: the
    high-pass and anti-alias filter states (``scipy.signal.sosfilt`` ``zi``), the noise stream
    (drawn row by row from ``rng``), the mains phase (drawn once, first) and time, and the
    sampling phase. Any split of a record therefore gives the same samples, bit for bit, as one
    call with the whole record.

    Parameters
    ----------
    transducers : list of Transducer
        One per channel.
    full_scale : array (n_channels,)
        ± range of each channel (the quantisation range).
    fs : float
        DAQ sample rate [Hz].
    decimation : int
        Physics steps per sample.
    aa : AntiAliasFilter
        The anti-alias filter.
    rng : numpy.random.Generator
        The run's DAQ noise generator.
    """

    def __init__(self, transducers, full_scale, *, fs, decimation, aa, rng):
        self.transducers = list(transducers)
        self.full_scale = np.asarray(full_scale, dtype=float)
        self.decimation = int(decimation)
        self.physics_rate = fs * decimation
        self._rng = rng
        self._hp = [
            _highpass_sos(t.highpass_hz, self.physics_rate)
            if _highpass_active(t, self.physics_rate)
            else None
            for t in self.transducers
        ]
        self._hp_zi = [None] * len(self.transducers)
        self._aa = aa.sos(fs, self.physics_rate)
        self._aa_zi = None
        rms = np.array([t.noise_rms for t in self.transducers])
        self._noise_gain = rms * np.sqrt(self.physics_rate / (2.0 * aa.cutoff * fs))
        self._phase = [
            rng.uniform(0, 2 * np.pi) if t.mains_amplitude > 0 else 0.0 for t in self.transducers
        ]
        self.steps = 0  # physics steps processed so far

    def process(self, raw: np.ndarray) -> np.ndarray:
        """Condition the next ``raw`` (n_steps, n_channels) physics-rate values; returns the
        samples that fall in them (every ``decimation``-th step of the whole record).

        Parameters
        ----------
        raw : ndarray (n_steps, n_channels)
            The next physics-rate sensor values, in sensor units.
        """
        n_steps, n = raw.shape
        x = np.empty_like(raw, dtype=float)
        for j, t in enumerate(self.transducers):
            col = raw[:, j] * t.gain
            if self._hp[j] is not None:
                if self._hp_zi[j] is None:  # steady state for the first value (powered before)
                    self._hp_zi[j] = signal.sosfilt_zi(self._hp[j]) * col[0]
                col, self._hp_zi[j] = signal.sosfilt(self._hp[j], col, zi=self._hp_zi[j])
            x[:, j] = col
        # noise: white at the physics rate, scaled so its RMS after the anti-alias filter is
        # noise_rms
        x += self._rng.standard_normal((n_steps, n)) * self._noise_gain
        time = np.arange(self.steps, self.steps + n_steps) / self.physics_rate
        for j, t in enumerate(self.transducers):
            if t.mains_amplitude > 0:
                x[:, j] += t.mains_amplitude * np.sin(
                    2 * np.pi * t.mains_hz * time + self._phase[j]
                )
        if self._aa_zi is None:
            self._aa_zi = signal.sosfilt_zi(self._aa)[:, :, None] * x[0][None, None, :]
        x, self._aa_zi = signal.sosfilt(self._aa, x, axis=0, zi=self._aa_zi)
        first = -self.steps % self.decimation
        self.steps += n_steps
        sampled = x[first :: self.decimation].copy()
        for j, t in enumerate(self.transducers):
            if t.bits:
                lsb = 2.0 * self.full_scale[j] / 2**t.bits
                sampled[:, j] = np.round(sampled[:, j] / lsb) * lsb
        return sampled


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
    """Condition and sample a whole record of physics-rate sensor signals ``raw`` (n_steps,
    n_channels) at once (``Acquisition(...).process(raw)``).

    Returns ``(sampled, peak)``: the sampled channels (ceil(n_steps / decimation), n_channels)
    and each channel's peak magnitude among them (for the transducer-range interlock).

    Parameters
    ----------
    raw : ndarray (n_steps, n_channels)
        Physics-rate sensor values, in sensor units.
    transducers : list of Transducer
        One per channel.
    full_scale : ndarray (n_channels,)
        ± range of each channel, in channel units (the quantisation range).
    fs : float
        DAQ sample rate in Hz.
    decimation : int
        Physics steps per sample.
    aa : AntiAliasFilter
        The anti-alias filter.
    rng : numpy.random.Generator
        The run's DAQ noise generator.
    """
    chain = Acquisition(transducers, full_scale, fs=fs, decimation=decimation, aa=aa, rng=rng)
    sampled = chain.process(raw)
    return sampled, np.abs(sampled).max(axis=0)
