"""Drive-iteration policies for the ``vrig/`` gymnasium environments: the gains of each iteration.

A policy is built for one environment (it reads the env's :class:`~vrig.envs.ActionLayout`),
``reset()`` at the start of each episode and called with each observation; it returns a valid
flat action (gains in the env's range). All of them work on any action mode (``bands``,
``channels``, ``scalar``, ``complex``): band-wise decisions are averaged where the mode has no
bands; in ``complex`` mode the phases are :meth:`Policy.phases` (0 unless a policy sets them:
then the episode is the ``bands`` one, bit for bit).

* :class:`FixedGain` - the classic: the same gain every iteration.
* :class:`DecreasingGain` - ``max(floor, start * decay**n)``.
* :class:`AdaptiveBandGain` - per band: cut the gain when the band's error grew, raise it
  slowly while it falls.
* :class:`SecantBandGain` - per band the secant step from the observed realised / predicted
  response-change ratio (``change_ratio``, ``change_phase``, env v2): ``g_b = scale / |rho_b|``
  (and the phase ``-arg rho_b`` in ``complex`` mode), a model update through the gains.
* :class:`BandRatioPolicy` - the learned one: per band ``g_b = exp(theta_b + alpha * change_b +
  beta * (error_b + 1) + gamma * n)`` from the observed log10 band-error ratio (``error_b``), its
  change over the last iteration (``change_b``) and the iteration index ``n`` (in ``complex``
  mode also a learned phase per band, ``phi_b``); parameters found
  by :func:`~vrig.policies.search.cross_entropy_search` (``benchmarks/learned_iteration.py``
  trains it). No GPU, no deep-learning library.

Every gain and parameter is a finite real number: a complex one (whose imaginary part a
float conversion would drop, with only NumPy's ``ComplexWarning`` to say so) is a
:class:`TypeError`, also when a policy's :meth:`Policy.gains` or :meth:`Policy.phases` returns
one. None of these policies takes complex gains: a phase is the ``complex`` action mode's
:meth:`Policy.phases`, given apart from the gain.

An episode of a policy is played by :func:`~vrig.policies.episodes.run_episode`.
"""

from __future__ import annotations

import numpy as np

from ..reconstruction.defaults import DEFAULT_GAIN

__all__ = [
    "AdaptiveBandGain",
    "BandRatioPolicy",
    "DecreasingGain",
    "FixedGain",
    "Policy",
    "SecantBandGain",
]


def _real_array(value, what: str) -> np.ndarray:
    """``value`` as a float array of finite real numbers, or a TypeError/ValueError naming
    ``what`` (a complex value is refused, never cast to its real part)."""
    arr = np.asarray(value)
    if arr.dtype.kind == "c":
        raise TypeError(
            f"{what} must be real, got a complex value ({value!r}): the imaginary part would be "
            "dropped; a phase is the 'complex' action mode's Policy.phases"
        )
    if arr.dtype.kind not in "iuf":
        raise TypeError(f"{what} must be a real number (or numbers), got {value!r}")
    arr = arr.astype(float)
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{what} must be finite, got {value!r}")
    return arr


def _real(value, what: str) -> float:
    """``value`` as one finite real float (see :func:`_real_array`)."""
    arr = _real_array(value, what)
    if arr.ndim != 0:
        raise TypeError(f"{what} must be one number, got an array of shape {arr.shape}")
    return float(arr)


class Policy:
    """Base class: ``reset()`` per episode, ``policy(obs) -> action``.

    Parameters
    ----------
    env : gymnasium.Env
        A :class:`vrig.envs.DriveIterationEnv` (or a wrapper of one); its action layout sets the
        shape of the actions.
    """

    name = "policy"

    def __init__(self, env):
        self.layout = env.unwrapped.layout

    def reset(self) -> None:
        """Forget the episode's state (called by :func:`~vrig.policies.episodes.run_episode`
        after ``env.reset``)."""

    def gains(self, obs) -> np.ndarray:  # pragma: no cover - abstract
        """Gains per drive channel and band (n_inputs, n_bands), or anything broadcasting.

        Parameters
        ----------
        obs : dict of str to ndarray
            The environment's observation (``iteration``, ``band_error``,
            ``band_error_change``, ...; see :class:`vrig.envs.DriveIterationEnv`).
        """
        raise NotImplementedError

    def reidentify(self, obs) -> bool:
        """Whether to re-identify the inverse model before the next iteration (default: never).

        Parameters
        ----------
        obs : dict of str to ndarray
            The environment's observation (``iteration``, ``band_error``,
            ``band_error_change``, ...; see :class:`vrig.envs.DriveIterationEnv`).
        """
        return False

    def phases(self, obs):
        """Phases [rad] per drive channel and band (n_inputs, n_bands), or anything broadcasting,
        for the ``"complex"`` action mode (> 0: phase lead; clipped to the env's ``phase_max``;
        default 0: the ``"bands"`` update). Not called in the other modes.

        Parameters
        ----------
        obs : dict of str to ndarray
            The environment's observation (``iteration``, ``band_error``,
            ``band_error_change``, ...; see :class:`vrig.envs.DriveIterationEnv`).
        """
        return 0.0

    def __call__(self, obs) -> np.ndarray:
        lay = self.layout
        shape = (lay.n_inputs, lay.n_bands)
        g = np.broadcast_to(_real_array(self.gains(obs), f"{self.name}: gains"), shape)
        if lay.mode == "channels":
            g = g.mean(axis=1)
        elif lay.mode == "scalar":
            g = np.array([g.mean()])
        phases = None
        if lay.mode == "complex":
            phases = np.broadcast_to(_real_array(self.phases(obs), f"{self.name}: phases"), shape)
            phases = np.clip(phases, -lay.phase_max, lay.phase_max)
        return lay.action(
            np.clip(g, lay.low, lay.high), phases, reidentify=self.reidentify(obs)
        )

    def __repr__(self) -> str:
        return self.name


class FixedGain(Policy):
    """The same gain every iteration (what :func:`vrig.reconstruct` does).

    Parameters
    ----------
    env : gymnasium.Env
        A :class:`vrig.envs.DriveIterationEnv` (or a wrapper of one); its action layout sets the
        shape of the actions.
    gain : float, optional
        The gain applied to every band and drive channel (default: ``vrig reconstruct``'s
        built-in, :data:`vrig.reconstruction.defaults.DEFAULT_GAIN`).
    """

    def __init__(self, env, gain: float = DEFAULT_GAIN):
        super().__init__(env)
        self.gain = _real(gain, "FixedGain: gain")
        self.name = f"fixed {self.gain:g}"

    def gains(self, obs):
        """The fixed gain, every iteration.

        Parameters
        ----------
        obs : dict of str to ndarray
            The environment's observation (``iteration``, ``band_error``,
            ``band_error_change``, ...; see :class:`vrig.envs.DriveIterationEnv`).
        """
        return self.gain


class DecreasingGain(Policy):
    """``gain_n = max(floor, start * decay**(n))`` for the update after iteration n.

    Parameters
    ----------
    env : gymnasium.Env
        A :class:`vrig.envs.DriveIterationEnv` (or a wrapper of one); its action layout sets the
        shape of the actions.
    start : float, optional
        Gain of the update after IT00.
    decay : float, optional
        Factor applied per iteration.
    floor : float, optional
        Smallest gain.
    """

    def __init__(self, env, start: float = 1.2, decay: float = 0.85, floor: float = 0.5):
        super().__init__(env)
        self.start, self.decay, self.floor = (
            _real(v, f"DecreasingGain: {k}")
            for k, v in (("start", start), ("decay", decay), ("floor", floor))
        )
        self.name = f"decreasing {self.start:g}x{self.decay:g}^n"

    def gains(self, obs):
        """``max(floor, start * decay**n)`` with n the observed iteration.

        Parameters
        ----------
        obs : dict of str to ndarray
            The environment's observation (``iteration``, ``band_error``,
            ``band_error_change``, ...; see :class:`vrig.envs.DriveIterationEnv`).
        """
        n = float(obs["iteration"][0])
        return max(self.floor, self.start * self.decay**n)


class AdaptiveBandGain(Policy):
    """Per band: multiply the gain by ``shrink`` when the band's error grew in the last
    iteration (any output channel), else by ``grow``; gains kept in [``low``, ``high``].

    Parameters
    ----------
    env : gymnasium.Env
        A :class:`vrig.envs.DriveIterationEnv` (or a wrapper of one); its action layout sets the
        shape of the actions.
    start : float, optional
        Gain of every band at the first update.
    shrink : float, optional
        Factor applied to a band's gain when its error grew.
    grow : float, optional
        Factor applied to a band's gain otherwise.
    low, high : float, optional
        Range the gains are kept in.
    """

    def __init__(
        self,
        env,
        start: float = 0.8,
        shrink: float = 0.5,
        grow: float = 1.1,
        low: float = 0.1,
        high: float = 1.2,
    ):
        super().__init__(env)
        given = {"start": start, "shrink": shrink, "grow": grow, "low": low, "high": high}
        real = {k: _real(v, f"AdaptiveBandGain: {k}") for k, v in given.items()}
        self.start, self.shrink, self.grow = real["start"], real["shrink"], real["grow"]
        self.low, self.high = real["low"], real["high"]
        self.name = "adaptive per band"
        self.reset()

    def reset(self):
        """Forget the gains of the last episode (the next call starts from ``start``)."""
        self._g = None

    def gains(self, obs):
        """The per-band gains after this observation's error changes.

        Parameters
        ----------
        obs : dict of str to ndarray
            The environment's observation (``iteration``, ``band_error``,
            ``band_error_change``, ...; see :class:`vrig.envs.DriveIterationEnv`).
        """
        lay = self.layout
        if self._g is None or float(obs["iteration"][0]) == 0:
            self._g = np.full((lay.n_inputs, lay.n_bands), self.start)
            return self._g.copy()
        grew = np.asarray(obs["band_error_change"]).max(axis=0) > 0  # (n_bands,)
        self._g = np.clip(
            self._g * np.where(grew, self.shrink, self.grow)[None, :], self.low, self.high
        )
        return self._g.copy()


class SecantBandGain(Policy):
    """Per band the secant step of the observed response-change ratio (env v2's
    ``change_ratio`` and ``change_phase``).

    The last correction moved the response by ``rho_b`` times what it aimed at in band ``b``
    (:func:`vrig.envs.task.response_change_ratios`); on a linear rig ``rho_b`` is the
    rig-to-model mismatch there, whatever the gain was, so the gain ``1 / rho_b`` would remove
    the band's error in one step. The policy plays ``g_b = clip(scale / |rho_b|, low, high)``,
    ``|rho_b|`` the geometric mean over the output channels (the same gain for every drive
    channel), and in the ``"complex"`` action mode the phase ``-arg rho_b`` (mean over the
    outputs; clipped to the env's ``phase_max``). Nothing is remembered between iterations: at
    IT00 (nothing observed yet: ``rho = 1``) and in a band with no predicted change it plays
    ``start``.

    Parameters
    ----------
    env : gymnasium.Env
        A :class:`vrig.envs.DriveIterationEnv` (v2, or a wrapper of one); its action layout
        sets the shape of the actions.
    start : float, optional
        Gain of every band at the first update (after IT00).
    scale : float, optional
        Fraction of the secant step (1: the full step; < 1 under-relaxed).
    low, high : float, optional
        Range the gains are kept in.
    """

    def __init__(
        self, env, start: float = 0.8, scale: float = 1.0, low: float = 0.1, high: float = 2.0
    ):
        super().__init__(env)
        if not (0 < low <= high) or scale <= 0 or start <= 0:
            raise ValueError(
                f"need start > 0, scale > 0 and 0 < low <= high, got start={start}, "
                f"scale={scale}, low={low}, high={high}"
            )
        self.start, self.scale = float(start), float(scale)
        self.low, self.high = float(low), float(high)
        self.name = "secant gain (observed)"

    def gains(self, obs):
        """``scale / |rho_b|`` per band (``start`` at IT00 and where nothing was predicted).

        Parameters
        ----------
        obs : dict of str to ndarray
            The environment's observation (``iteration``, ``change_ratio``, ...; see
            :class:`vrig.envs.DriveIterationEnv`).
        """
        log_rho = np.asarray(obs["change_ratio"], float).mean(axis=0)  # (n_bands,)
        phase = np.asarray(obs["change_phase"], float)
        # IT00, a failed step, a band with nothing predicted: observed as 0 and 0 (rho = 1)
        unobserved = ~np.any(obs["change_ratio"], axis=0) & ~np.any(phase, axis=0)
        g = np.where(unobserved, self.start, self.scale * 10.0 ** (-log_rho))
        return np.clip(g, self.low, self.high)[None, :]

    def phases(self, obs):
        """``-arg rho_b`` per band (mean over the outputs), the phase of the secant step.

        Parameters
        ----------
        obs : dict of str to ndarray
            The environment's observation (``change_phase``, ...; see
            :class:`vrig.envs.DriveIterationEnv`).
        """
        return -np.asarray(obs["change_phase"], float).mean(axis=0)[None, :]


class BandRatioPolicy(Policy):
    """Learned per-band gains as a function of the observed band-error ratios.

    ``g_b = clip(exp(theta_b + alpha * change_b + beta * (error_b + 1) + gamma * n))``, with
    ``error_b`` the log10 band-error ratio and ``change_b`` its change over the last iteration
    (both taken as the maximum over output channels) and ``n`` the iteration index.
    ``params = [theta_1 .. theta_B, alpha, beta, gamma]``; in the ``"complex"`` action mode
    followed by a phase per band ``[phi_1 .. phi_B]`` [rad] (the same for every drive channel and
    iteration: a fixed correction of the inverse model's phase error per band).

    Parameters
    ----------
    env : gymnasium.Env
        A :class:`vrig.envs.DriveIterationEnv` (or a wrapper of one); its action layout sets the
        shape of the actions.
    params : array_like, shape (n_params(env),)
        ``[theta_1 .. theta_B, alpha, beta, gamma]`` (see above), plus ``[phi_1 .. phi_B]`` in
        the ``"complex"`` action mode.
    """

    def __init__(self, env, params):
        super().__init__(env)
        p = _real_array(params, "BandRatioPolicy: params")
        if p.shape != (self.n_params(env),):
            raise ValueError(f"params must have shape ({self.n_params(env)},), got {p.shape}")
        self.params = p
        self.name = "learned (CEM)"

    @staticmethod
    def n_params(env) -> int:
        """Length of the parameter vector for ``env``: its number of bands plus 3 (plus the
        number of bands again in the ``"complex"`` action mode: the phases).

        Parameters
        ----------
        env : gymnasium.Env
            A :class:`vrig.envs.DriveIterationEnv` (or a wrapper of one); its action layout sets the
            shape of the actions.
        """
        lay = env.unwrapped.layout
        return lay.n_bands + 3 + (lay.n_bands if lay.mode == "complex" else 0)

    @staticmethod
    def initial(env, gain: float = DEFAULT_GAIN) -> np.ndarray:
        """Parameters of the fixed gain ``gain`` (a starting point for the search; phases 0).

        Parameters
        ----------
        env : gymnasium.Env
            A :class:`vrig.envs.DriveIterationEnv` (or a wrapper of one); its action layout sets the
            shape of the actions.
        gain : float, optional
            The fixed gain the parameters reproduce.
        """
        gain = _real(gain, "BandRatioPolicy.initial: gain")
        if gain <= 0:
            raise ValueError(f"BandRatioPolicy.initial: gain must be > 0 (its log), got {gain:g}")
        p = np.zeros(BandRatioPolicy.n_params(env))
        p[: env.unwrapped.layout.n_bands] = np.log(gain)
        return p

    def gains(self, obs):
        """The learned per-band gains for this observation (same for every drive channel).

        Parameters
        ----------
        obs : dict of str to ndarray
            The environment's observation (``iteration``, ``band_error``,
            ``band_error_change``, ...; see :class:`vrig.envs.DriveIterationEnv`).
        """
        nb = self.layout.n_bands
        theta, (alpha, beta, gamma) = self.params[:nb], self.params[nb : nb + 3]
        err = np.asarray(obs["band_error"], float).max(axis=0)
        change = np.asarray(obs["band_error_change"], float).max(axis=0)
        n = float(obs["iteration"][0])
        x = theta + alpha * change + beta * (err + 1.0) + gamma * n
        return np.exp(np.clip(x, -20, 5))[None, :]

    def phases(self, obs):
        """The learned phase per band [rad] (``params[n_bands + 3:]``; ``"complex"`` mode only),
        the same for every drive channel.

        Parameters
        ----------
        obs : dict of str to ndarray
            The environment's observation (``iteration``, ``band_error``,
            ``band_error_change``, ...; see :class:`vrig.envs.DriveIterationEnv`).
        """
        nb = self.layout.n_bands
        return self.params[nb + 3 : 2 * nb + 3][None, :]
