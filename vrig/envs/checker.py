"""Gymnasium's passive env checker, made safe for a reset (or step) that raises.

:class:`gymnasium.wrappers.PassiveEnvChecker` (which ``gymnasium.make`` puts around every env
unless ``disable_env_checker=True``) marks its first reset as checked *before* it calls the env's
``reset``, and keeps the reset's result to compare with the first step's. When that first reset
raises (a :class:`~vrig.RigLimitError`: the target's IT00 drive trips the rig), the checker is
left half-initialised: the next reset is no longer checked, nothing is kept, and the first
``step`` after any later, successful reset raises ``TypeError: cannot unpack non-iterable
NoneType object`` from inside gymnasium - the env is broken for good although it is in a valid
state. A drive-iteration reset can legitimately raise (an explicit target beyond the rig's
limits), so the registered ``vrig/`` ids apply :class:`ResetSafeEnvChecker` instead: the same
checks, with a first reset or step that raises leaving the checker as it was before the call (the
next one is checked as the first). Their entry point is :func:`make_checked`, and their spec says
``disable_env_checker=True`` so that ``gymnasium.make`` does not add the stock checker on top;
:class:`ResetSafeEnvChecker` is always applied (``gymnasium.make(id, disable_env_checker=True)``
does not remove it: it only checks, never changes, what passes through).
"""

from __future__ import annotations

from gymnasium.wrappers import PassiveEnvChecker

from .drive_iteration import DriveIterationEnv

__all__ = ["ResetSafeEnvChecker", "make_checked"]


class ResetSafeEnvChecker(PassiveEnvChecker):
    """:class:`gymnasium.wrappers.PassiveEnvChecker` whose first ``reset`` / ``step`` counts
    only once it returned: one that raises leaves the checker as it was before the call.

    Parameters
    ----------
    env : gymnasium.Env
        The env to check.
    """

    def __init__(self, env):
        super().__init__(env)

    def reset(self, *, seed=None, options=None):
        """As :meth:`gymnasium.wrappers.PassiveEnvChecker.reset`; a first reset that raises is
        not recorded as the checked one.

        Parameters
        ----------
        seed : int, optional
            As the env's ``reset``.
        options : dict, optional
            As the env's ``reset``.
        """
        first = not self.checked_reset
        try:
            return super().reset(seed=seed, options=options)
        except BaseException:
            if first:  # gymnasium set the flag before the call: the next reset is the first
                self.checked_reset, self._previous_data = False, None
            raise

    def step(self, action):
        """As :meth:`gymnasium.wrappers.PassiveEnvChecker.step`; a first step that raises is
        not recorded as the checked one.

        Parameters
        ----------
        action : array_like
            As the env's ``step``.
        """
        first = not self.checked_step
        try:
            return super().step(action)
        except BaseException:
            if first:
                self.checked_step = False
            raise

    @property
    def spec(self):
        """The env's spec as it is: ``disable_env_checker`` stays True, so that
        ``gymnasium.make(env.spec)`` does not add the stock checker on top of this one
        (:func:`make_checked` applies it)."""
        return self.env.spec


def make_checked(**kwargs) -> ResetSafeEnvChecker:
    """The entry point of the registered ``vrig/`` ids: a :class:`DriveIterationEnv` inside
    :class:`ResetSafeEnvChecker` (``gymnasium.make`` adds ``OrderEnforcing`` and ``TimeLimit``
    around it, as around any env).

    Parameters
    ----------
    **kwargs
        The :class:`DriveIterationEnv` arguments.

    Returns
    -------
    ResetSafeEnvChecker
    """
    return ResetSafeEnvChecker(DriveIterationEnv(**kwargs))
