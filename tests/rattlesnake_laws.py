"""The pseudo-inverse transient control law, in Rattlesnake's three forms, for the adapter's tests.

Written from the published description of Rattlesnake's transient pseudo-inverse control: the
drive spectrum is the pseudo-inverse of the FRF matrix times the specification's spectrum, line
by line, ``D(f) = pinv(H(f)) S(f)``, and the drive is its inverse real FFT. The FRF comes on the
system identification's (coarser) frequency grid; it is brought to the specification's grid by
linear interpolation between its lines. (Rattlesnake's own example goes through the FRF's
impulse response, zero-padded to the specification's length: that needs an FRF valid up to
Nyquist, and vrig's identification records are band-limited to the identification band, so the
lines above it are leakage whose impulse response wraps round to negative time.)

Rattlesnake's conventions: channels first, time last; ``transfer_function`` is (lines,
responses, drives); ``extra_parameters`` is free text, here ``rcond: <float>`` lines; the
output is oversampled by ``output_oversample_factor`` (zeros appended to the spectrum).

Also malformed laws, one per mistake the adapter must name.
"""

from __future__ import annotations

import numpy as np


def _rcond(extra_parameters: str) -> float:
    """``rcond: x`` from the extra parameters (default 1e-6)."""
    for line in extra_parameters.splitlines():
        key, _, value = line.partition(":")
        if key.strip() == "rcond":
            return float(value)
    return 1e-6


def frf_on_grid(transfer_function, frequency_spacing, n):
    """The FRF (lines, responses, drives) at the lines of an ``n``-sample record's real FFT,
    interpolated linearly (real and imaginary parts) between the identification's lines
    ``k * frequency_spacing``, held at the last line beyond it; frequencies in units of the
    sample rate, so ``frequency_spacing`` is given as a fraction of it."""
    lines = np.arange(transfer_function.shape[0]) * frequency_spacing
    grid = np.fft.rfftfreq(n)
    flat = transfer_function.reshape(transfer_function.shape[0], -1)
    out = np.empty((grid.size, flat.shape[1]), dtype=complex)
    for k in range(flat.shape[1]):
        out[:, k] = np.interp(grid, lines, flat[:, k].real) + 1j * np.interp(
            grid, lines, flat[:, k].imag
        )
    return out.reshape(grid.size, *transfer_function.shape[1:])


def pinv_drive(sample_rate, specification_signals, frequency_spacing, transfer_function, k, extra):
    """``irfft(pinv(H) S)`` on the specification's grid (see the module docstring), oversampled
    ``k`` times."""
    spec = np.asarray(specification_signals, dtype=float)
    n = spec.shape[-1]
    frf = frf_on_grid(transfer_function, frequency_spacing / sample_rate, n)
    spectrum = np.fft.rfft(spec, axis=-1).T  # (n // 2 + 1, responses)
    drive = np.einsum("fij,fj->fi", np.linalg.pinv(frf, rcond=_rcond(extra)), spectrum)
    return np.fft.irfft(drive, n=n * k, axis=0).T * k  # (drives, n x k)


def pinv_function(
    sample_rate,
    specification_signals,
    frequency_spacing,
    transfer_function,
    noise_response_cpsd,
    noise_reference_cpsd,
    sysid_response_cpsd,
    sysid_reference_cpsd,
    multiple_coherence,
    frames,
    total_frames,
    output_oversample_factor,
    extra_parameters="",
    last_excitation_signals=None,
    last_response_signals=None,
):
    """The function form."""
    return pinv_drive(
        sample_rate,
        specification_signals,
        frequency_spacing,
        transfer_function,
        output_oversample_factor,
        extra_parameters,
    )


def pinv_generator():
    """The generator form: primed, then sent the function form's arguments as one tuple."""
    drive = None
    while True:
        args = yield drive
        (fs, spec, df, frf, *_, oversample, extra, _last_excitation, _last_response) = args
        drive = pinv_drive(fs, spec, df, frf, oversample, extra)


class PinvClass:
    """The class form: made with the identification, updated by ``system_id_update``, asked
    for the drive by ``control``."""

    def __init__(
        self,
        sample_rate,
        specification_signals,
        output_oversample_factor,
        extra_parameters,
        frequency_spacing,
        transfer_function,
        noise_response_cpsd,
        noise_reference_cpsd,
        sysid_response_cpsd,
        sysid_reference_cpsd,
        multiple_coherence,
        frames,
        total_frames,
        last_excitation_signals=None,
        last_response_signals=None,
    ):
        self.sample_rate, self.spec = sample_rate, specification_signals
        self.oversample, self.extra = output_oversample_factor, extra_parameters
        self.updates = 0
        self.system_id_update(
            frequency_spacing,
            transfer_function,
            noise_response_cpsd,
            noise_reference_cpsd,
            sysid_response_cpsd,
            sysid_reference_cpsd,
            multiple_coherence,
            frames,
            total_frames,
        )

    def system_id_update(
        self,
        frequency_spacing,
        transfer_function,
        noise_response_cpsd,
        noise_reference_cpsd,
        sysid_response_cpsd,
        sysid_reference_cpsd,
        multiple_coherence,
        frames,
        total_frames,
    ):
        self.updates += 1
        self.drive = pinv_drive(
            self.sample_rate,
            self.spec,
            frequency_spacing,
            transfer_function,
            self.oversample,
            self.extra,
        )

    def control(self, last_excitation_signals=None, last_response_signals=None):
        return self.drive


CALLS: list = []


def recording_function(*args):
    """The function form, keeping every call's arguments in ``CALLS``."""
    CALLS.append(args)
    return pinv_function(*args)


# --- malformed laws ---------------------------------------------------------------------------
def too_few_arguments(sample_rate, specification_signals, transfer_function):
    """A function law missing most of the interface."""
    return specification_signals


def wrong_shape(*args):
    """Returns the drive time-first (vrig's convention, not Rattlesnake's)."""
    return pinv_function(*args).T[:, :1]


def not_finite(*args):
    """Returns a drive with a NaN in it."""
    drive = pinv_function(*args)
    drive[0, 5] = np.nan
    return drive


class NoControl:
    """A class law without ``control``."""

    def __init__(self, *args):
        pass

    def system_id_update(self, *args):
        pass


NOT_A_LAW = 42
