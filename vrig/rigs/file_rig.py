"""A rig adapter that plays drives by file: offline iteration with a real (or remote) rig.

Each ``run`` writes the drive as an RPC III ``.drv`` file (``RUNnnn.drv``, in run order)
into a folder, obtains the response file for it and reads it back. The response comes from
``respond(drive_path) -> response_path`` (a function that plays the file on the rig, or asks an
operator), so the whole reconstruction can run against a lab that exchanges files.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np

from ..timehistory import TimeHistory
from .limits import check_drive_limits
from .spec import ChannelSpec

__all__ = ["FileRig"]


class FileRig:
    """Offline rig: drives written to files, responses read from files.

    Parameters
    ----------
    folder : path
        Where drive files are written (created if needed).
    inputs, outputs : sequence of ChannelSpec
        The drive and response channels (names, units, full scales).
    fs : float
        Sample rate of drives and responses [Hz].
    respond : callable
        ``respond(drive_path) -> response_path``: plays the drive file and returns the path of the
        response file (RPC III, CSV, MAT or NPZ; see :func:`vrig.io.read`).
    bandwidth : (low, high) Hz
        The test band (default 0 .. fs/4).
    name : str
        The rig's name (as a shipped rig's, e.g. in a test folder's summary).
    """

    def __init__(
        self,
        folder,
        inputs,
        outputs,
        fs: float,
        respond: Callable[[Path], Path],
        *,
        bandwidth=None,
        name: str = "file-rig",
    ):
        if not callable(respond):
            raise TypeError("respond must be a callable respond(drive_path) -> response_path")
        self.folder = Path(folder)
        self.folder.mkdir(parents=True, exist_ok=True)
        self.inputs = tuple(inputs)
        self.outputs = tuple(outputs)
        for c in (*self.inputs, *self.outputs):
            if not isinstance(c, ChannelSpec):
                raise TypeError("inputs and outputs must be ChannelSpec objects")
        self.fs = float(fs)
        self.respond = respond
        self.bandwidth = tuple(bandwidth) if bandwidth is not None else (0.0, self.fs / 4)
        self.name = name
        self._count = 0

    def run(self, drive, *, seed=None) -> TimeHistory:
        """Write the drive file, obtain and read the response (``seed`` is ignored).

        Parameters
        ----------
        drive : ndarray or TimeHistory
            The drive, (n_samples, n_inputs) in the drive channels' units, at ``fs``.
        seed : int, optional
            Ignored (the response is whatever ``respond`` returns).
        """
        from .. import io

        data = np.asarray(getattr(drive, "data", drive), dtype=float)
        if data.ndim == 1:
            data = data[:, None]
        if data.ndim != 2 or data.shape[1] != len(self.inputs):
            raise ValueError(f"drive must have shape (N, {len(self.inputs)}), got {data.shape}")
        check_drive_limits(self.inputs, data, fs=self.fs, what="the drive file")
        th = TimeHistory(
            data, self.fs, [c.name for c in self.inputs], [c.unit for c in self.inputs]
        )
        path = self.folder / f"RUN{self._count:03d}.drv"  # run order: IDDRV first, then ITxxDRV
        self._count += 1
        io.write_rpc3(path, th, time_type="DRIVE")
        response = io.read(self.respond(path))
        if response.fs != self.fs or response.n_samples != th.n_samples:
            raise ValueError(
                f"response file has {response.n_samples} samples at {response.fs:g} Hz; expected "
                f"{th.n_samples} at {self.fs:g} Hz"
            )
        if response.n_channels != len(self.outputs):
            raise ValueError(
                f"response file has {response.n_channels} channels, expected {len(self.outputs)}"
            )
        return TimeHistory(
            response.data, self.fs, [c.name for c in self.outputs], [c.unit for c in self.outputs]
        )
