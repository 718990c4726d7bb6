# ---
# jupyter:
#   jupytext:
#     text_representation:
#       extension: .py
#       format_name: percent
#   kernelspec:
#     display_name: Python 3
#     language: python
#     name: python3
# ---

# %% [markdown]
# # The benchmark suite and a method plugin
#
# The benchmark runner (`python -m benchmarks run`, or `vrig bench run` in a source checkout)
# runs every rig × method × desired response × seed as one **record** (η0 at IT00 and after the
# iterations, iterations to tolerance, RMS error, damage ratio, the normal and inverse modelling
# errors, fit time, model size), in parallel processes or on a Ray cluster, resumable after an
# interrupt, and writes the records (JSON, CSV), a Markdown **leaderboard** and plots.
#
# Methods are **plugins**. This tutorial writes one — an inverse FIR filter with ridge
# regularisation — and ranks it against the built-in inverse ARX on the shaker rig.
#
# **Needs a source checkout**: the `benchmarks` package is not part of the installed wheel. The
# runs here are the `--quick` settings on one rig and two or three methods (short records);
# `--no-thesis` skips the reference text's tables, the longest part of a run.

# %%
# %matplotlib inline
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import vrig

ROOT = Path(vrig.__file__).resolve().parents[1]  # the source checkout
assert (ROOT / "benchmarks" / "runner").is_dir(), "this tutorial needs a source checkout of vrig"
WORK = Path(tempfile.mkdtemp())
ENV = dict(os.environ, PYTHONPATH=os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")]))


def bench(*args):
    """Run ``python -m benchmarks ARGS`` and print what it prints."""
    done = subprocess.run([sys.executable, "-m", "benchmarks", *args], cwd=ROOT, env=ENV,
                          capture_output=True, text=True, check=True)
    print(done.stdout)


bench("list")

# %% [markdown]
# ## A method
#
# A method has two obligations (the `vrig.reconstruction.Method` protocol):
#
# * `identify(iddrv, idres)` — fit from the processed identification drive and response
#   (`vrig.TimeHistory`, at the model rate);
# * `drive(response)` — the drive (an array, samples × drive channels) it predicts for a
#   response.
#
# `describe()` (one line for the leaderboard) and `model_size()` (number of coefficients) are
# optional. The plugin module registers a **factory** under a name with
# `benchmarks.runner.register_method`; the factory gets the rig and the simulation band, so a
# method can adapt to them. The shipped example plugin `benchmarks/plugins/inverse_fir.py` is an
# inverse FIR fitted by plain least squares (`fir` above); ours has fewer taps and adds a ridge
# penalty (a smoother, smaller filter).

# %%
plugin = WORK / "ridge_fir.py"
plugin.write_text('''"""Tutorial plugin: an inverse FIR filter fitted by ridge regression."""

import numpy as np

from benchmarks.runner import register_method


class RidgeFir:
    """drive(t) = sum_k C_k response(t + lead - k), k = 0 .. taps-1, ridge-regularised."""

    def __init__(self, taps=32, lead=8, ridge=1e-3):
        self.taps, self.lead, self.ridge = taps, lead, ridge

    def _lagged(self, r):  # columns r(t + lead - k) for every k and channel; edges held
        pad = np.pad(r, ((self.taps, self.lead), (0, 0)), mode="edge")
        n, s = r.shape[0], self.taps + self.lead
        return np.hstack([pad[s - k : s - k + n] for k in range(self.taps)])

    def identify(self, iddrv, idres):
        X = self._lagged(np.asarray(idres.data))
        scale = np.mean(X * X)  # penalty relative to the regressors' power
        A = X.T @ X + self.ridge * scale * len(X) * np.eye(X.shape[1])
        self.coef = np.linalg.solve(A, X.T @ np.asarray(iddrv.data))

    def drive(self, response):
        return self._lagged(np.asarray(response.data)) @ self.coef

    def describe(self):
        return f"inverse FIR, {self.taps} taps, lead {self.lead}, ridge {self.ridge:g} (tutorial)"

    def model_size(self):
        return self.coef.size


register_method("ridge-fir", lambda rig, band: RidgeFir(), description="inverse ridge FIR",
                linear=True)
''')
bench("list", "--plugin", str(plugin))

# %% [markdown]
# ## A run
#
# Rank it against the built-in inverse ARX and the least-squares FIR on the shaker. Records
# run in worker processes; each loads the plugin again from its file (plugins are never
# pickled), so the same works on a Ray cluster.

# %%
out = WORK / "bench"
bench("run", "--quick", "--rigs", "shaker", "--methods", "arx", "fir", "ridge-fir",
      "--plugin", str(plugin), "--out", str(out), "--no-thesis", "--no-plots", "--workers", "1",
      "--quiet")
print((out / "leaderboard.md").read_text())

# %% [markdown]
# Whether the penalty and the shorter filter help is what the leaderboard is for: on this quick
# shaker record they do not — the plain 48-tap FIR ranks first (the table above is computed
# while this page is built).
#
# The leaderboard's first table ranks the methods by their mean best η0 over all records (a
# failed record counts as 100 %); one table per rig gives every measure. The records are in
# `records.json`/`records.csv` and one JSON file per record under `records/`: running the same
# command again computes nothing (it resumes), and adding a method or rig computes only the new
# records. `python -m benchmarks run --quick` (without `--rigs`/`--methods`) is the full quick
# leaderboard (48 records; it prints its slowest records and its wall time at the end),
# `python -m benchmarks run` the full one;
# `benchmarks/README.md` describes the rest (Ray, severities, speed suites).
