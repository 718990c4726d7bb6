"""Example plugin: an inverse FIR filter fitted by least squares (the README's example)."""

import numpy as np

from benchmarks.runner import register_method


class InverseFir:
    """drive(t) = sum_k C_k response(t + lead - k), k = 0 .. taps-1 (all channels)."""

    def __init__(self, taps=48, lead=12):
        self.taps, self.lead = taps, lead

    def _lagged(self, r):  # columns r(t + lead - k) for every k and channel; edges held
        pad = np.pad(r, ((self.taps, self.lead), (0, 0)), mode="edge")
        n, s = r.shape[0], self.taps + self.lead
        return np.hstack([pad[s - k : s - k + n] for k in range(self.taps)])

    def identify(self, iddrv, idres):
        self.coef, *_ = np.linalg.lstsq(self._lagged(idres.data), iddrv.data, rcond=None)

    def drive(self, response):
        return self._lagged(response.data) @ self.coef

    def describe(self):
        return f"inverse FIR, {self.taps} taps, lead {self.lead} (example plugin)"

    def model_size(self):
        return self.coef.size


register_method("fir", lambda: InverseFir(), description="inverse FIR, example plugin", linear=True)
