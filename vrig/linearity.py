"""Is this system non-linear enough for NARX to be worth it? (reference text §5.8 and beyond)

:func:`check_linearity` works on any drive/response records (a lab's measured TimeHistory
pairs, no rig needed); :func:`check_rig_linearity` makes the records on a rig with
:meth:`rig.run <vrig.rigs.MujocoRig.run>`; :func:`linearity_drives` designs the drives for
either. Every test is judged against the noise floor *measured* on the same data (a replay of
the same drive), never against a fixed tolerance.

The records (``records`` maps a name to a ``(drive, response)`` pair of TimeHistory, all the
same length and sample rate; the drive relations are checked):

========== ================================================================================
``u``      a zero-mean random drive in the band (required)
``repeat`` the same drive ``u`` played again (another noise realisation; required): the
           noise floor of every test is measured from ``y_u - y_repeat``
``2u``     ``2 u`` (any factor a != 0, 1 is accepted; the measured factor is used)
``-u``     ``-u``
``0``      zero drive: the drive-independent part of the response (offsets, mains hum,
           gravity preload) is subtracted from every response; without it each response's
           mean is subtracted instead
``b``      a constant offset b != 0 on every drive channel (the text's mean-level test)
``u+b``    ``u`` (zero mean over the analysis window) plus that offset
========== ================================================================================

The tests, per response channel:

(a) **Mean level** (§5.8, Billings and Voon): with ``ū = 0`` and ``b != 0`` a linear system has
    the same mean response to ``b`` and to ``u + b``. ``Δ = mean(y_{u+b}) - mean(y_b)``
    [response unit] is compared with its noise floor, the standard error of the mean of
    ``y_u - y_repeat`` (batch means over 10 blocks; that difference has the same noise
    variance as Δ's two independent runs): ``z = |Δ| / se``. Evidence if ``z > 5``.
(b) **Scaling / superposition**: with ``ỹ = y - y_0`` (the drive-related response), a linear
    system has ``ỹ_{au} = a ỹ_u``. The residual ``r_a = ỹ_{au} - a ỹ_u`` is compared with the
    rms it would have from noise alone, ``σ sqrt(1 + a² + (1 - a)²)`` (with a ``0`` record;
    ``σ sqrt(1 + a²)`` without), where the per-run noise rms ``σ = rms(y_u - y_repeat) / √2``:
    ``ratio = rms(r_a) / noise rms``. Evidence if the larger of the ``2u`` and ``-u`` ratios
    exceeds ``K = 3`` (distortion power 9 times the noise power: far beyond the few-% sampling
    scatter of an rms over hundreds of independent samples).
(c) **Coherence**: the multiple coherence γ² of each response with all the drives (Welch
    cross-spectra, ~1 s Hann segments; for one drive it is ``scipy.signal.coherence``). The
    power of ``ỹ_u`` that is not linearly related to the drive, ``Σ (1 - γ²) P_ỹỹ`` over the
    band, would be all noise for a linear system; the noise power is ``Σ P_n`` from the
    replay (``P_n`` = half the PSD of ``y_u - y_repeat``, doubled when ``y_0`` is
    subtracted). ``ratio = sqrt(incoherent / noise power)``; evidence if ``> K = 3``. Low
    coherence at a good signal-to-noise ratio is what non-linear distortion looks like.
(d) **ARX vs NARX** (the text's own practical method, §5.8): the first 70 % of the ``u``
    analysis window identifies, the last 30 % is held out. ARX orders 1..6 are scanned on the
    held-out free-run error η0 (eq. 5-28, DC corrected); a quadratic NARX of the chosen order
    is fitted (the text: "the optimal model order as found in the linear case ... along with a
    quadratic polynomial. If the modelling results improved, but remained unsatisfactory, a
    cubic model could be used"), and a cubic one when it has at most 12 input regressors; the
    better one on the held-out data counts. Both are ``kind="input-polynomial"`` (past outputs
    enter linearly, so the free run is as stable as the ARX part; the full quadratic NARX's
    least-squares free run diverged on the damper). Evidence if the NARX beats the ARX
    *clearly*: its held-out η0 is
    at least 20 % lower (a practically relevant improvement) **and** the improvement exceeds
    ``K = 3`` times η0 of the noise alone (what a perfect model would score on this record).
    The order scan favours the ARX (its order is chosen on the held-out data): conservative.

**Verdict** (per response channel; the system is non-linear if any channel is): with the
scaling test run, *non-linear* when the scaling test shows evidence **and** at least one other
test agrees, or when the scaling ratio alone exceeds ``K² = 9`` (distortion power 81 times
the noise power: even a noise floor misjudged by a factor K in rms cannot explain it; one
replay misjudges a floor that holds a periodic disturbance such as mains hum by up to ~1.6);
without the scaling test, when at least two tests show evidence. Below ``K²`` one test alone
is not enough: a single test can be fooled (a residual transient, an unlucky noise-floor
estimate), two independent ones rarely are. Thresholds are set from the statistics of the
noise-floor estimates, not tuned on any rig.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from scipy import signal
from scipy.signal import windows

from .spectra import frf_h1
from .timehistory import TimeHistory

__all__ = [
    "K_NOISE",
    "NARX_GAIN",
    "Z_MEAN",
    "LinearityResult",
    "check_linearity",
    "check_rig_linearity",
    "linearity_drives",
]

K_NOISE = 3.0
"""Scaling, coherence and NARX tests: evidence beyond this multiple of the measured noise floor
(an amplitude ratio)."""
Z_MEAN = 5.0
"""Mean-level test: evidence beyond this many standard errors of the mean."""
NARX_GAIN = 0.2
"""ARX vs NARX: the NARX's held-out η0 must be at least this fraction lower than the ARX's."""
DEFAULT_LEVEL = 0.10
"""Rig helper: the random drive's rms as a fraction of each drive channel's full scale (as the
pseudo-field drive, :mod:`vrig.desired.pseudo_field`); ``2u`` then peaks near 70 % of full scale."""
_RAMP_S = 1.0
_SETTLE_S = 1.0
_BLOCKS = 10
_HOLDOUT = 0.3
_MAX_ORDER = 6
_CUBIC_MAX_REGRESSORS = 12  # a cubic NARX only on few input regressors (C(12 + 3, 3) = 455 terms)
_KEYS = ("u", "repeat", "2u", "-u", "0", "b", "u+b")


# ---------------------------------------------------------------------------------------------
# drives
# ---------------------------------------------------------------------------------------------
def linearity_drives(
    fs: float,
    band: tuple[float, float],
    rms,
    *,
    seconds: float = 8.0,
    offset=None,
    ramp: float = _RAMP_S,
    settle: float = _SETTLE_S,
    seed: int = 0,
    names=None,
    units=None,
) -> dict[str, TimeHistory]:
    """The drives of a linearity check: ``{"u", "repeat", "2u", "-u", "0", "b", "u+b"}``.

    ``u`` is a periodic band-limited random signal (flat PSD over ``band`` [Hz], ``rms`` per
    drive channel, one fixed ``seed``: every record shares the same random signal, only the
    scaling differs) of ``seconds`` length, with exactly zero mean over that period. It is
    preceded by ``ramp + settle`` seconds of its own cyclic continuation, the first ``ramp``
    seconds faded in (half cosine), so the analysis window (everything after them,
    ``skip=ramp + settle`` in :func:`check_linearity`) sees a linear system in its periodic
    steady state (to within ``exp(-settle / τ)`` for its longest time constant τ), whose mean
    response is exactly the static gain times 0. ``b`` is ``offset`` (default: ``rms``) per
    channel, faded in over the ramp.

    Parameters
    ----------
    fs : float
        Sample rate in Hz.
    band : tuple of float
        ``(low, high)`` band of ``u`` in Hz.
    rms : float or array_like
        RMS of ``u`` per drive channel, in the drive unit.
    seconds : float, optional
        Length of the analysis window in s.
    offset : float or array_like, optional
        The offset b per drive channel, in the drive unit (default ``rms``).
    ramp : float, optional
        Fade-in, in s.
    settle : float, optional
        Settling time after the fade-in, in s.
    seed : int, optional
        Seed of the random signal (the same for every record).
    names, units : sequence of str, optional
        Drive channel names and units.
    """
    from .signals import flat_psd, random_drive

    rms = np.atleast_1d(np.asarray(rms, dtype=float))
    n_in = rms.size
    offset = rms.copy() if offset is None else np.broadcast_to(np.asarray(offset, float), (n_in,))
    if not (seconds > 0 and ramp >= 0 and settle >= 0):
        raise ValueError(
            f"seconds must be > 0, ramp and settle >= 0, got {seconds!r}, {ramp!r}, {settle!r}"
        )
    n, r, m = round(seconds * fs), round(ramp * fs), round(settle * fs)
    u = random_drive(flat_psd(band), n, fs, channels=n_in, seed=seed).data
    u = (u - u.mean(axis=0)) * rms / np.sqrt(np.mean((u - u.mean(axis=0)) ** 2, axis=0))
    w = np.ones((r + m + n, 1))
    w[:r, 0] = windows.hann(2 * r + 1)[:r]  # the rising half of a raised cosine
    u = u[np.arange(-(r + m), n) % n] * w  # the cyclic continuation, faded in
    b = w * offset
    names = list(names) if names is not None else [f"drive{k + 1}" for k in range(n_in)]
    units = list(units) if units is not None else ["-"] * n_in
    out = {"u": u, "repeat": u, "2u": 2 * u, "-u": -u, "0": 0 * u, "b": b, "u+b": u + b}
    return {k: TimeHistory(v, fs, names, units) for k, v in out.items()}


# ---------------------------------------------------------------------------------------------
# result
# ---------------------------------------------------------------------------------------------
@dataclass
class LinearityResult:
    """Every figure of a linearity check (see the module docstring), per response channel.

    Arrays are (n_outputs,) unless noted; NaN where a test was not run. ``verdict`` is
    ``"linear"`` or ``"non-linear"``.

    Attributes
    ----------
    names, units : tuple of str
        Response channel names and units.
    fs : float
        Sample rate in Hz.
    band : tuple of float
        ``(low, high)`` analysis band in Hz.
    window_s : float
        Length of the analysis window in s.
    repeat_error : ndarray
        ``rms(y_u - y_repeat) / rms(ỹ_u)`` in %.
    noise_rms : ndarray
        Per-run noise RMS σ, in the response unit.
    mean_delta, mean_se : ndarray
        Mean-level test (a): Δ and its standard error, in the response unit.
    mean_z : ndarray
        ``|Δ| / se`` [-].
    offset : ndarray or None
        The offset b per drive channel, in the drive unit (None without the ``b`` records).
    scaling : dict
        Scaling test (b) per record key (``"2u"``, ``"-u"``): ``{"factor", "error" [%],
        "noise" [%], "ratio" (array)}``.
    coherence_f : ndarray (F,)
        Frequencies of the coherence in Hz.
    coherence, coherence_noise : ndarray (F, ny)
        Multiple coherence γ² and the γ² that noise alone would leave [-].
    coherence_mean : ndarray
        Mean γ² in the band [-].
    coherence_ratio : ndarray
        Coherence test (c): ``sqrt(incoherent / noise power)`` [-].
    arx_order : int or None
        ARX order chosen on the held-out data (None: test (d) not run or no ARX fitted).
    eta_arx, eta_narx, eta_noise : ndarray
        Held-out free-run η0 of the ARX, of the NARX and of the noise alone, in %.
    narx_kind : str
        Which NARX counted, e.g. ``"degree 2, input-polynomial"``.
    evidence : dict of str to ndarray of bool
        Per test name: whether each response channel shows evidence.
    channel_verdict : list of str
        ``"linear"`` or ``"non-linear"`` per response channel.
    verdict : str
        ``"non-linear"`` if any channel is, else ``"linear"``.
    notes : list of str
        What could not be run, and why.
    info : dict
        How the records were made (rig, drive), when known.
    heldout : dict
        The held-out records of test (d) for the first channel: ``"t"``, ``"measured"``,
        ``"arx"``, ``"narx"``.
    """

    names: tuple[str, ...]
    units: tuple[str, ...]
    fs: float
    band: tuple[float, float]
    window_s: float
    repeat_error: np.ndarray  # rms(y_u - y_repeat) / rms(ỹ_u) [%]
    noise_rms: np.ndarray  # σ, per-run noise rms [unit]
    mean_delta: np.ndarray  # Δ [unit]
    mean_se: np.ndarray  # standard error of Δ [unit]
    mean_z: np.ndarray
    offset: np.ndarray | None  # b per drive channel [drive unit]
    scaling: dict  # key ("2u", "-u") -> {"factor", "error" [%], "noise" [%], "ratio" (array)}
    coherence_f: np.ndarray  # (F,) [Hz]
    coherence: np.ndarray  # (F, ny) multiple coherence γ² [-]
    coherence_noise: np.ndarray  # (F, ny) γ² that noise alone would leave [-]
    coherence_mean: np.ndarray  # mean γ² in the band [-]
    coherence_ratio: np.ndarray
    arx_order: int | None
    eta_arx: np.ndarray  # held-out free-run η0 [%]
    eta_narx: np.ndarray
    eta_noise: np.ndarray
    narx_kind: str
    evidence: dict  # test -> bool array (ny,)
    channel_verdict: list
    verdict: str
    notes: list = field(default_factory=list)
    info: dict = field(default_factory=dict)
    heldout: dict = field(default_factory=dict)  # "t", "measured", "arx", "narx" (first channel)

    # ----------------------------------------------------------------- text
    def table(self) -> str:
        """The evidence as a text table, one block per test, ending with the verdict line."""
        w = max(12, *(len(n) for n in self.names))
        lines = self._header_lines(w)
        lines.append("")
        lines += self._mean_level_lines(w)
        lines.append("")
        lines += self._scaling_lines(w)
        lines.append("")
        lines += self._coherence_lines(w)
        lines.append("")
        lines += self._narx_lines(w)
        lines.append("")
        lines += self._verdict_lines(w)
        return "\n".join(lines)

    def _flag(self, test: str, k: int) -> str:
        """One test's verdict on channel ``k`` for the table."""
        ev = self.evidence.get(test)
        return "n/a" if ev is None else ("NON-LINEAR" if ev[k] else "linear")

    def _header_lines(self, w: int) -> list[str]:
        """Run info, analysis window and band, per-channel noise and repeatability."""
        lines = [f"{key:<10} {value}" for key, value in self.info.items()]
        lines.append(
            f"window     {self.window_s:g} s analysed at {self.fs:g} Hz; band "
            f"{self.band[0]:g}-{self.band[1]:g} Hz"
        )
        lines.append("")
        lines.append(f"{'channel':<{w}}  noise rms  repeat error")
        for k, n in enumerate(self.names):
            lines.append(
                f"{n:<{w}}  {self.noise_rms[k]:.4g} {self.units[k]}  {self.repeat_error[k]:.3g} %"
            )
        return lines

    def _mean_level_lines(self, w: int) -> list[str]:
        """Test (a): the mean-level shift under ``u + b``."""
        if self.offset is None:
            return ["(a) mean level: not run (no 'b' and 'u+b' records)"]
        b = ", ".join(f"{x:.4g}" for x in self.offset)
        lines = [f"(a) mean level (§5.8), offset b = [{b}], evidence if z > {Z_MEAN:g}"]
        for k, n in enumerate(self.names):
            lines.append(
                f"{n:<{w}}  Δ = {self.mean_delta[k]:+.4g} {self.units[k]} "
                f"(se {self.mean_se[k]:.3g} {self.units[k]}), z = {self.mean_z[k]:.3g}  "
                f"-> {self._flag('mean level', k)}"
            )
        return lines

    def _scaling_lines(self, w: int) -> list[str]:
        """Test (b): the residual of the scaled runs against the noise alone."""
        if not self.scaling:
            return ["(b) scaling: not run (no '2u' or '-u' record)"]
        lines = [f"(b) scaling, residual rms vs noise alone, evidence if ratio > {K_NOISE:g}"]
        for k, n in enumerate(self.names):
            parts = [
                f"{key} (a = {s['factor']:.3g}): {s['error'][k]:.3g} % vs noise "
                f"{s['noise'][k]:.3g} %, ratio {s['ratio'][k]:.3g}"
                for key, s in self.scaling.items()
            ]
            lines.append(f"{n:<{w}}  " + "; ".join(parts) + f"  -> {self._flag('scaling', k)}")
        return lines

    def _coherence_lines(self, w: int) -> list[str]:
        """Test (c): the incoherent power in band against the noise power."""
        lines = [
            f"(c) coherence in band, incoherent vs noise power, evidence if ratio > {K_NOISE:g}"
        ]
        for k, n in enumerate(self.names):
            lines.append(
                f"{n:<{w}}  mean γ² {self.coherence_mean[k]:.4f}, ratio "
                f"{self.coherence_ratio[k]:.3g}  -> {self._flag('coherence', k)}"
            )
        return lines

    def _narx_lines(self, w: int) -> list[str]:
        """Test (d): held-out free run of an ARX against a NARX of the same order."""
        if self.arx_order is None:
            return ["(d) ARX vs NARX: no ARX could be fitted (see notes)"]
        lines = [
            f"(d) held-out free run: ARX({self.arx_order}) vs NARX({self.arx_order}, "
            f"{self.narx_kind}), evidence if NARX ≥ {100 * NARX_GAIN:g} % lower "
            f"and better by > {K_NOISE:g} x noise η0"
        ]
        for k, n in enumerate(self.names):
            lines.append(
                f"{n:<{w}}  η0 ARX {self.eta_arx[k]:.3g} %, NARX {self.eta_narx[k]:.3g} %, "
                f"noise {self.eta_noise[k]:.3g} %  -> {self._flag('narx', k)}"
            )
        return lines

    def _verdict_lines(self, w: int) -> list[str]:
        """The decision rule, the per-channel verdicts, the notes and the overall verdict."""
        rule = (
            "non-linear if the scaling test and at least one other test show evidence, or the "
            f"scaling ratio alone exceeds {K_NOISE**2:g}"
            if self.scaling
            else "non-linear if at least two tests show evidence"
        )
        lines = [f"rule: {rule} (per channel)"]
        for k, n in enumerate(self.names):
            lines.append(f"{n:<{w}}  {self.channel_verdict[k]}")
        for note in self.notes:
            lines.append(f"note: {note}")
        lines.append(f"verdict: {self.verdict}")
        return lines

    def __str__(self) -> str:
        return self.table()

    # ----------------------------------------------------------------- plot
    def figure(self):
        """A matplotlib Figure (Agg; not registered with pyplot): coherence, residual ratios,
        held-out free runs."""
        from matplotlib.figure import Figure

        fig = Figure(figsize=(10.0, 7.5), layout="constrained")
        (ax_c, ax_r), (ax_t, ax_b) = fig.subplots(2, 2)
        f = self.coherence_f
        for k, n in enumerate(self.names):
            (line,) = ax_c.plot(f, self.coherence[:, k], lw=1.0, label=f"{n}: measured")
            ax_c.plot(
                f, self.coherence_noise[:, k], lw=1.0, ls="--", color=line.get_color(),
                label=f"{n}: linear reference",
            )  # fmt: skip
        ax_c.axvspan(self.band[0], self.band[1], color="0.92", zorder=0)
        ax_c.set_xlim(0, min(f[-1], 1.5 * self.band[1]) if f.size else 1)
        ax_c.set_ylim(0, 1.05)
        ax_c.set_xlabel("frequency [Hz]")
        ax_c.set_ylabel("coherence γ² [-]")
        ax_c.set_title("(c) drive → response coherence")
        ax_c.legend(fontsize=7)

        labels, values = [], []
        tests = [("mean level", self.mean_z / Z_MEAN)]
        tests += [(f"scaling {key}", sc["ratio"] / K_NOISE) for key, sc in self.scaling.items()]
        tests += [("coherence", self.coherence_ratio / K_NOISE)]
        if self.arx_order is not None:  # both NARX criteria: the smaller decides
            gain = (self.eta_arx - self.eta_narx) / np.maximum(K_NOISE * self.eta_noise, 1e-12)
            rel = (1 - self.eta_narx / self.eta_arx) / NARX_GAIN
            tests += [("NARX gain", np.minimum(gain, rel))]
        for name, ratio in tests:
            for k, n in enumerate(self.names):
                if np.isfinite(ratio[k]):
                    labels.append(f"{name}\n{n}" if len(self.names) > 1 else name)
                    values.append(max(ratio[k], 1e-3))
        y = np.arange(len(values))
        ax_r.barh(y, values, color=["C3" if v > 1 else "C0" for v in values])
        ax_r.axvline(1.0, color="k", lw=1.0)
        ax_r.set_xscale("log")
        ax_r.set_yticks(y, labels, fontsize=7)
        ax_r.set_xlabel("test statistic / its threshold [-] (> 1: evidence)")
        ax_r.set_title(f"evidence (verdict: {self.verdict})")

        h = self.heldout
        if h:
            unit = self.units[0]
            ax_t.plot(h["t"], h["measured"], color="k", lw=1.0, label="measured")
            ax_t.plot(h["t"], h["arx"], lw=1.0, label=f"ARX({self.arx_order})")
            ax_t.plot(h["t"], h["narx"], lw=1.0, label=f"NARX({self.arx_order}, {self.narx_kind})")
            ax_t.set_xlabel("time [s]")
            ax_t.set_ylabel(f"{self.names[0]} [{unit}]")
            ax_t.legend(fontsize=7)
        ax_t.set_title("(d) held-out free run, first channel")

        sc = h.get("scaling") if h else None
        if sc is not None:
            ax_b.plot(
                sc["t"], sc["expected"], color="k", lw=1.0, label=f"{sc['factor']:.3g} x ỹ(u)"
            )
            ax_b.plot(sc["t"], sc["measured"], lw=1.0, label=f"ỹ({sc['key']})")
            ax_b.set_xlabel("time [s]")
            ax_b.set_ylabel(f"{self.names[0]} [{self.units[0]}]")
            ax_b.legend(fontsize=7)
        ax_b.set_title("(b) scaling, first channel (1 s excerpt)")
        return fig

    def plot(self, path) -> Path:
        """Write :meth:`figure` to ``path`` atomically (its suffix gives the format).

        Parameters
        ----------
        path : str or os.PathLike
            The image file; its suffix gives the format.
        """
        from .plots import save_figure

        return save_figure(self.figure(), path)


# ---------------------------------------------------------------------------------------------
# the check
# ---------------------------------------------------------------------------------------------
def _pair(key, value, first):
    try:
        drive, response = value
    except (TypeError, ValueError):
        raise ValueError(f"records[{key!r}] must be a (drive, response) pair") from None
    out = []
    for what, th in (("drive", drive), ("response", response)):
        if not isinstance(th, TimeHistory):
            raise ValueError(
                f"records[{key!r}] {what} must be a TimeHistory, got {type(th).__name__}"
            )
        out.append(th)
    drive, response = out
    if drive.n_samples != response.n_samples or drive.fs != response.fs:
        raise ValueError(
            f"records[{key!r}]: drive ({drive.n_samples} samples at {drive.fs:g} Hz) and response "
            f"({response.n_samples} at {response.fs:g} Hz) differ"
        )
    if first is not None:
        d0, r0 = first
        if (
            drive.data.shape != d0.data.shape
            or response.data.shape != r0.data.shape
            or (drive.fs != d0.fs)
        ):
            raise ValueError(
                f"records[{key!r}] ({drive.n_samples} samples x {drive.n_channels} drives -> "
                f"{response.n_channels} responses at {drive.fs:g} Hz) does not match records['u'] "
                f"({d0.n_samples} x {d0.n_channels} -> {r0.n_channels} at {d0.fs:g} Hz)"
            )
    return drive.data, response.data


def _rms(x, axis=0):
    return np.sqrt(np.mean(np.asarray(x) ** 2, axis=axis))


def _factor(d, u, key):
    """The factor a with ``d = a u`` (least squares); the relation must hold to 1e-3."""
    a = float(np.sum(d * u) / np.sum(u * u))
    if _rms(d - a * u).max() > 1e-3 * _rms(a * u).max() or not np.isfinite(a):
        raise ValueError(
            f"records[{key!r}]: its drive is not a scaled copy of records['u']'s drive (residual "
            f"{_rms(d - a * u).max():.3g} after the best factor {a:.4g})"
        )
    return a


def _multiple_coherence(x, y, fs, nperseg):
    """Multiple coherence of every output with all inputs (F, ny); for one input it equals
    ``scipy.signal.coherence``. Also returns f and the output PSDs."""
    h1 = _h1(x, y, fs, nperseg)
    return h1.f, h1.coherence, np.real(np.einsum("fii->fi", h1.gyy))


def _h1(x, y, fs, nperseg):
    """The H1 estimate of the check (``S_uu`` inverted wherever numerically non-singular:
    :func:`vrig.spectra.frf_h1` with ``regularisation="line"``)."""
    return frf_h1(x, y, fs=fs, nperseg=nperseg, regularisation="line")


def _fit_models(u, y, fs, notes):
    """Held-out free-run η0 of the best ARX (orders 1..6) and a quadratic NARX of its order."""
    from identification import Arx, Narx, metrics
    from identification.errors import IdentificationError, SimulationDivergedError

    n = u.shape[0]
    split = round((1 - _HOLDOUT) * n)
    ui, yi, uv, yv = u[:split], y[:split], u[split:], y[split:]
    skip = _MAX_ORDER + 1
    ny = y.shape[1]
    if split < 20 * (u.shape[1] + ny) * (_MAX_ORDER + 1) or n - split < 4 * skip:
        notes.append(f"record too short ({n} samples) for the ARX/NARX comparison")
        return None, np.full(ny, np.nan), np.full(ny, np.nan), "", {}

    def run(model):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            try:
                model.fit(ui, yi)
                sim = model.simulate(uv, yv[: model.max_lag_])
            except (IdentificationError, SimulationDivergedError, np.linalg.LinAlgError) as exc:
                return None, str(exc).split("\n")[0]
        eta = metrics.qantim_fit_dc(yv[skip:], sim[skip:])
        if not np.all(np.isfinite(eta)):
            return None, "non-finite free run"
        return (np.atleast_1d(eta), sim), None

    best, best_order = None, None
    for order in range(1, _MAX_ORDER + 1):
        got, _why = run(Arx(order))
        if got is not None and (best is None or got[0].mean() < best[0].mean()):
            best, best_order = got, order
    if best is None:
        notes.append("no ARX of order 1..6 gave a bounded held-out free run")
        return None, np.full(ny, np.nan), np.full(ny, np.nan), "", {}
    # past outputs enter linearly: a stable linear part gives a bounded free run. Quadratic
    # first (§5.8); cubic too when its term set is small (the text's next step)
    n_input_regs = u.shape[1] * (best_order + 1)
    degrees = (2, 3) if n_input_regs <= _CUBIC_MAX_REGRESSORS else (2,)
    eta_narx, sim_narx, kind, whys = np.full(ny, np.inf), np.full_like(yv, np.nan), "", []
    for degree in degrees:
        got, why = run(Narx(best_order, degree, kind="input-polynomial"))
        if got is None:
            whys.append(f"degree {degree}: {why}")
        elif got[0].mean() < eta_narx.mean():
            eta_narx, sim_narx = got
            kind = f"degree {degree}, input-polynomial"
    if not kind:
        notes.append(f"no NARX({best_order}) could be used ({'; '.join(whys)}): no evidence")
    t = (split + np.arange(yv.shape[0])) / fs
    heldout = {"t": t, "measured": yv[:, 0], "arx": best[1][:, 0], "narx": sim_narx[:, 0]}
    return best_order, best[0], eta_narx, kind, heldout


def check_linearity(
    records: Mapping,
    *,
    band: tuple[float, float] | None = None,
    skip: float = 0.0,
    models: bool = True,
) -> LinearityResult:
    """Decide from drive/response records whether a system is linear (module docstring).

    Parameters
    ----------
    records : mapping
        ``name -> (drive, response)`` TimeHistory pairs, names from ``u`` (required),
        ``repeat`` (required: the same drive again, for the noise floor), ``2u``, ``-u``,
        ``0``, ``b``, ``u+b`` (see the module docstring; :func:`linearity_drives` designs
        them). Every record has the same length, sample rate and channels.
    band : (low, high) Hz, optional
        Where the coherence is judged; default: where the ``u`` drive has at least 1 % of its
        largest PSD line.
    skip : float
        Seconds at the start of every record left out of the analysis (a fade-in; the rig
        helper's ramp).
    models : bool
        Run the ARX vs NARX comparison (d) (the slowest test).

    Returns
    -------
    LinearityResult
        Every figure, :meth:`~LinearityResult.table`, :meth:`~LinearityResult.plot` and the
        ``verdict``.
    """
    d, y, (_, yu_th), s0 = _analysis_windows(records, skip)
    u, fs, names, units = d["u"], yu_th.fs, yu_th.names, yu_th.units
    ny, n = len(names), d["u"].shape[0]
    notes: list[str] = []
    floor = _NoiseFloor(d, y)
    evidence: dict[str, np.ndarray] = {}

    mean_delta, mean_se, mean_z, offset = _mean_level_test(d, y, floor, notes)
    if "b" in d:
        evidence["mean level"] = mean_z > Z_MEAN
    scaling = _scaling_test(d, floor)
    if scaling:
        evidence["scaling"] = np.max([s["ratio"] for s in scaling.values()], axis=0) > K_NOISE
    coh = _coherence_test(u, floor, fs, band)
    band = coh["band"]
    evidence["coherence"] = coh["ratio"] > K_NOISE

    arx_order, eta_arx, eta_narx, kind, heldout = (
        None,
        np.full(ny, np.nan),
        np.full(ny, np.nan),
        "",
        {},
    )
    eta_noise = np.full(ny, np.nan)
    if models:
        arx_order, eta_arx, eta_narx, kind, heldout = _fit_models(u, floor.yt, fs, notes)
        if heldout:
            heldout["t"] = heldout["t"] + s0 / fs
        if arx_order is not None:
            eta_noise = _model_noise(floor, n)
            gain = eta_arx - eta_narx
            evidence["narx"] = (eta_narx <= (1 - NARX_GAIN) * eta_arx) & (
                gain > K_NOISE * eta_noise
            )
    if scaling and "scaling" in evidence:
        heldout = dict(heldout)
        heldout["scaling"] = _scaling_example(scaling, floor, n, fs, s0)

    channel_verdict = _channel_verdicts(evidence, scaling, ny)
    if not scaling and len(evidence) < 2:
        notes.append("fewer than two tests could be run: the verdict 'linear' is weak")
    verdict = "non-linear" if "non-linear" in channel_verdict else "linear"
    return LinearityResult(
        names=tuple(names),
        units=tuple(units),
        fs=fs,
        band=band,
        window_s=n / fs,
        repeat_error=floor.repeat_error,
        noise_rms=floor.sigma,
        mean_delta=mean_delta,
        mean_se=mean_se,
        mean_z=mean_z,
        offset=offset,
        scaling=scaling,
        coherence_f=coh["f"],
        coherence=coh["gamma"],
        coherence_noise=coh["gamma_ref"],
        coherence_mean=coh["mean"],
        coherence_ratio=coh["ratio"],
        arx_order=arx_order,
        eta_arx=eta_arx,
        eta_narx=eta_narx,
        eta_noise=eta_noise,
        narx_kind=kind,
        evidence=evidence,
        channel_verdict=channel_verdict,
        verdict=verdict,
        notes=notes,
        heldout=heldout,
    )


def _analysis_windows(records, skip: float):
    """The validated records cut to the analysed window: drives ``d`` and responses ``y`` by
    name, the ``u`` pair as given, and the first analysed sample ``s0``."""
    if not isinstance(records, Mapping):
        raise ValueError("records must be a mapping name -> (drive, response)")
    unknown = sorted(set(records) - set(_KEYS))
    if unknown:
        raise ValueError(f"unknown record names {unknown}; known: {list(_KEYS)}")
    for need in ("u", "repeat"):
        if need not in records:
            raise ValueError(
                f"records need {need!r}"
                + (
                    ": the same drive played twice gives the noise floor every test is judged "
                    "against"
                    if need == "repeat"
                    else ""
                )
            )
    if ("b" in records) != ("u+b" in records):
        raise ValueError("the mean-level test needs both 'b' and 'u+b' records")
    du, yu_th = records["u"]
    _pair("u", (du, yu_th), None)
    fs = yu_th.fs
    s0 = round(skip * fs)
    if not 0 <= s0 < yu_th.n_samples - 64:
        raise ValueError(
            f"skip {skip!r} s leaves fewer than 64 of the {yu_th.n_samples} samples to analyse"
        )
    d, y = {}, {}
    for key in _KEYS:
        if key in records:
            dd, yy = _pair(key, records[key], (du, yu_th))
            d[key], y[key] = dd[s0:], yy[s0:]
    if np.max(_rms(d["u"])) == 0:
        raise ValueError("records['u'] has a zero drive")
    _factor(d["repeat"], d["u"], "repeat")
    if "0" in d and np.max(np.abs(d["0"])) > 1e-9 * np.max(np.abs(d["u"])):
        raise ValueError("records['0'] must have a zero drive")
    return d, y, (du, yu_th), s0


class _NoiseFloor:
    """The responses with the drive-independent part removed (``tilde``) and the per-run noise
    the tests are judged against, from the repeat (and the zero-drive record, if any)."""

    def __init__(self, d: dict, y: dict):
        self.y = y
        self.has0 = "0" in d
        self.base = y["0"] if self.has0 else None
        self.yt = self.tilde("u")
        self.sig = np.maximum(_rms(self.yt), 1e-300)
        self.diff = y["u"] - y["repeat"]
        sigma = _rms(self.diff - self.diff.mean(axis=0)) / math.sqrt(2)
        if self.has0:  # a zero-drive record is a noise realisation whose variance does not
            # depend on the phases of a periodic disturbance (mains hum), unlike a difference
            sigma = np.maximum(sigma, _rms(self.base - self.base.mean(axis=0)))
        self.sigma = np.maximum(sigma, 1e-12 * self.sig)
        self.repeat_error = 100 * _rms(self.diff) / self.sig
        self.c0 = 2.0 if self.has0 else 1.0  # noise variance of ỹ per run's noise variance

    def tilde(self, key):
        y = self.y[key]
        return y - self.base if self.has0 else y - y.mean(axis=0)


def _mean_level_test(d, y, floor: _NoiseFloor, notes: list):
    """(a) §5.8: the mean response to u + b minus the mean response to b, against the standard
    error of a mean from block means of the repeat difference."""
    ny = floor.yt.shape[1]
    nan = np.full(ny, np.nan)
    if "b" not in d:
        return nan, nan, nan, None
    db, dub = d["b"], d["u+b"]
    offset = db.mean(axis=0)
    if np.any(np.ptp(db, axis=0) > 1e-6 * np.maximum(np.abs(offset), 1e-300)):
        raise ValueError("records['b'] must hold a constant drive over the analysed window")
    if np.any(offset == 0):
        raise ValueError("records['b']: the offset b must be non-zero on every drive (§5.8)")
    rand = dub - db
    if np.any(np.abs(rand.mean(axis=0)) > 0.01 * _rms(rand)):
        notes.append(
            "the random part of 'u+b' has a mean above 1 % of its rms over the window: the "
            "mean-level test is biased by the static gain times that mean"
        )
    mean_delta = y["u+b"].mean(axis=0) - y["b"].mean(axis=0)
    blocks = np.array_split(floor.diff, _BLOCKS)
    bm = np.array([blk.mean(axis=0) for blk in blocks])
    mean_se = np.maximum(bm.std(axis=0, ddof=1) / math.sqrt(_BLOCKS), 1e-12 * floor.sig)
    return mean_delta, mean_se, np.abs(mean_delta) / mean_se, offset


def _scaling_test(d, floor: _NoiseFloor) -> dict:
    """(b) superposition: the response to a u against a x the response to u, per scaled record,
    against the noise that many runs put into the residual."""
    scaling = {}
    u, yt = d["u"], floor.yt
    for key in ("2u", "-u"):
        if key in d:
            a = _factor(d[key], u, key)
            r = floor.tilde(key) - a * yt
            nvar = (1 + a * a + (1 - a) ** 2) if floor.has0 else (1 + a * a)
            noise = floor.sigma * math.sqrt(nvar)
            ref = np.maximum(_rms(a * yt), 1e-300)
            scaling[key] = {
                "factor": a,
                "error": 100 * _rms(r) / ref,
                "noise": 100 * noise / ref,
                "ratio": _rms(r) / noise,
            }
    return scaling


def _coherence_test(u, floor: _NoiseFloor, fs: float, band) -> dict:
    """(c) the incoherent power in the band against a linear reference's: the best linear (H1)
    response to u plus the measured noise, through the same estimator (Welch's finite segments
    bias γ² low on any system with memory)."""
    yt, n, ny = floor.yt, u.shape[0], floor.yt.shape[1]
    nperseg = int(min(2 ** round(math.log2(fs)), n // 4))
    est = _h1(u, yt, fs, nperseg)
    f, gamma, pyy = est.f, est.coherence, np.real(np.einsum("fii->fi", est.gyy))
    if band is None:
        puu = np.real(np.einsum("fii->fi", est.gxx))
        active = np.flatnonzero(puu.max(axis=1) >= 0.01 * puu.max())
        band = (float(f[active[0]]), float(f[active[-1]]))
    band = (float(band[0]), float(band[1]))
    if not 0 <= band[0] < band[1] <= fs / 2:
        raise ValueError(f"band must satisfy 0 <= low < high <= fs/2 = {fs / 2:g} Hz, got {band}")
    inb = (f >= band[0]) & (f <= band[1]) & (f > 0)
    if not np.any(inb):
        raise ValueError(f"no spectral line in the band {band} Hz: use a longer record")
    h1 = np.where(inb[:, None, None], np.swapaxes(est.frf, 1, 2), 0.0)  # (F, nu, ny)
    h = np.roll(np.fft.irfft(h1, n=nperseg, axis=0), nperseg // 2, axis=0)
    y_lin = np.zeros_like(yt)
    for j in range(ny):
        for i in range(u.shape[1]):
            y_lin[:, j] += signal.fftconvolve(u[:, i], h[:, i, j])[nperseg // 2 : nperseg // 2 + n]
    y_ref = y_lin + floor.diff * math.sqrt(floor.c0 / 2)
    _, gamma_ref, pyy_ref = _multiple_coherence(u, y_ref, fs, nperseg)
    inc = np.sum(((1 - gamma) * pyy)[inb], axis=0)
    inc_ref = np.sum(((1 - gamma_ref) * pyy_ref)[inb], axis=0)
    return {
        "band": band,
        "f": f,
        "gamma": gamma,
        "gamma_ref": gamma_ref,
        "mean": gamma[inb].mean(axis=0),
        "ratio": np.sqrt(inc / np.maximum(inc_ref, 1e-300 + 1e-24 * inc)),
    }


def _model_noise(floor: _NoiseFloor, n: int) -> np.ndarray:
    """(d)'s noise floor: the η0 [%] the noise alone gives on the held-out part."""
    split = round((1 - _HOLDOUT) * n)
    yv = floor.yt[split:][_MAX_ORDER + 1 :]
    nv = (floor.diff[split:][_MAX_ORDER + 1 :]) * math.sqrt(floor.c0 / 2)
    nv = nv - nv.mean(axis=0)
    return 100 * np.abs(nv).sum(axis=0) / np.abs(yv - yv.mean(axis=0)).sum(axis=0)


def _scaling_example(scaling: dict, floor: _NoiseFloor, n: int, fs: float, s0: int) -> dict:
    """The first second of the scaling evidence on channel 0, for the plot."""
    key = "2u" if "2u" in scaling else "-u"
    m = min(n, round(fs))
    return {
        "key": key,
        "factor": scaling[key]["factor"],
        "t": (s0 + np.arange(m)) / fs,
        "expected": scaling[key]["factor"] * floor.yt[:m, 0],
        "measured": floor.tilde(key)[:m, 0],
    }


def _channel_verdicts(evidence: dict, scaling: dict, ny: int) -> list:
    """The rule: non-linear when the scaling test and one other agree, or the scaling ratio
    alone exceeds K_NOISE²; without a scaling test, two tests must agree."""
    others = [k for k in evidence if k != "scaling"]
    out = []
    for k in range(ny):
        count = sum(bool(evidence[t][k]) for t in others)
        if scaling:
            worst = max(sc["ratio"][k] for sc in scaling.values())
            nl = bool(evidence["scaling"][k]) and (count >= 1 or worst > K_NOISE**2)
        else:
            nl = count >= 2
        out.append("non-linear" if nl else "linear")
    return out


# ---------------------------------------------------------------------------------------------
# on a rig
# ---------------------------------------------------------------------------------------------
def check_rig_linearity(
    rig,
    *,
    level: float = DEFAULT_LEVEL,
    seconds: float = 8.0,
    band: tuple[float, float] | None = None,
    seed: int = 0,
    models: bool = True,
    progress: bool = False,
) -> LinearityResult:
    """Play the records of :func:`linearity_drives` on ``rig`` and :func:`check_linearity` them.

    The drive is flat band-limited random noise over ``band`` (default: the rig's simulation
    band, :func:`vrig.reconstruction.defaults.default_band`) with ``level`` x each drive channel's full scale
    rms (default 10 %; ``2u`` then peaks near 70 % of full scale), the offset b = that rms,
    ``seconds`` of analysis after a 1 s fade-in and 1 s of settling. One drive seed (``seed``) for every record;
    every run its own rig noise seed (``seed + 10_000 + i``). If a run trips an interlock the
    level is halved (at most three times) and every record is made again: the level used is in
    ``result.info``. Seven runs of ``seconds + 2`` s each.

    Parameters
    ----------
    rig : Rig
        The rig to play the drives on.
    level : float, optional
        RMS of ``u`` as a fraction of each drive channel's full scale.
    seconds : float, optional
        Length of the analysis window in s.
    band : tuple of float, optional
        ``(low, high)`` drive band in Hz (default the rig's simulation band).
    seed : int, optional
        Drive seed; run ``i``'s noise seed is ``seed + 10_000 + i``.
    models : bool, optional
        Run the ARX vs NARX comparison (d) (the slowest test).
    progress : bool, optional
        Show a progress bar over the runs on stderr (:mod:`vrig.progress`; ``False`` leaves an
        outer :func:`vrig.progress.enabled` in force, as ``vrig check-linearity`` sets it).
    """
    from .errors import RigLimitError
    from .progress import bar, enabled_if
    from .reconstruction.defaults import default_band

    if not (isinstance(level, (int, float)) and 0 < level <= 0.5):
        raise ValueError(f"level must be a fraction of full scale in (0, 0.5], got {level!r}")
    if not (isinstance(seconds, (int, float)) and math.isfinite(seconds) and seconds >= 2):
        raise ValueError(f"seconds must be >= 2, got {seconds!r}")
    band = tuple(default_band(rig)) if band is None else tuple(float(b) for b in band)
    full = np.array([c.full_scale for c in rig.inputs])
    last = None
    for _attempt in range(4):
        drives = linearity_drives(
            rig.fs, band, level * full, seconds=seconds, seed=seed,
            names=[c.name for c in rig.inputs], units=[c.unit for c in rig.inputs],
        )  # fmt: skip
        records = {}
        try:
            with enabled_if(progress), bar(len(drives), desc=f"{rig.name}: runs") as runs:
                for i, (key, drive) in enumerate(drives.items()):
                    records[key] = (drive, rig.run(drive, seed=seed + 10_000 + i))
                    runs.update(1)
        except RigLimitError as exc:
            last = exc
            level /= 2
            continue
        result = check_linearity(records, band=band, skip=_RAMP_S + _SETTLE_S, models=models)
        variant = getattr(rig, "variant", None)
        result.info = {
            "rig": f"{rig.name}" + (f" (variant {variant})" if variant else ""),
            "drive": f"flat random {band[0]:g}-{band[1]:g} Hz, {100 * level:.3g} % of full scale "
            f"rms, offset b = the same, seed {seed}; 7 runs of {seconds + _RAMP_S + _SETTLE_S:g} s",
        }
        return result
    raise last
