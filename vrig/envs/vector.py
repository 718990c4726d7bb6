"""A batched vector env: N drive-iteration envs on one rig, their rig runs played together.

:class:`DriveIterationVectorEnv` is a :class:`gymnasium.vector.SyncVectorEnv` whose ``step`` and
``reset`` first *prepare* every sub-env (:meth:`~vrig.envs.DriveIterationEnv.prepare_step`:
the next drive from the action; or :meth:`~vrig.envs.DriveIterationEnv.prepare_reset`: the
target and its IT00 drive), plays all the drives in one batched rig call
(:func:`vrig.reconstruction.engine.play_batch` -> :meth:`vrig.rigs.MujocoRig.run_batch`, across
threads), and then lets ``SyncVectorEnv`` do exactly what it always does - with each sub-env's
``step`` / ``reset`` *finishing* from the staged outcome instead of playing its own. So the
vector semantics (autoreset mode, ``reset_mask``, info merging, ``TimeLimit`` truncation) are
gymnasium's own, and the results are those of ``gymnasium.make_vec(id, n,
vectorization_mode="sync")`` (and ``"async"``) bit for bit (``tests/test_env_vector.py``). The
sub-envs share one rig and one identified inverse model. The new target records of the resetting
sub-envs (pseudo-field or service records: rig runs too) are made before, together, their rig
runs batched (:meth:`~vrig.envs.IterationPhysics.target_records`), while the step's iteration
drives already play beside them (a second thread, on the rig's other ``MjData``: every run is
seeded, so nothing depends on which runs overlap); then the IT00 drives play in one batch.

Every registered ``vrig/`` id names it as its ``vector_entry_point``, so
``gymnasium.make_vec("vrig/ShockAbsorber-v2", num_envs=8)`` builds it (pass
``vectorization_mode="sync"`` or ``"async"`` for gymnasium's own).
"""

from __future__ import annotations

import os
import threading

import gymnasium as gym
import numpy as np
from gymnasium.vector import AutoresetMode, SyncVectorEnv
from gymnasium.vector.utils import iterate
from gymnasium.wrappers import TimeLimit

from ..reconstruction.engine import play_batch
from .drive_iteration import PHYSICS_OPTIONS, DriveIterationEnv

__all__ = ["DriveIterationVectorEnv"]


class _Staged(gym.Wrapper):
    """Finishes ``step`` / ``reset`` from an outcome staged by the vector env (the drive was
    prepared and played in the batch); without one it is transparent."""

    def __init__(self, env: DriveIterationEnv):
        super().__init__(env)
        self.outcome = None  # ("step" | "reset", outcome) or None

    def step(self, action):
        """See :meth:`DriveIterationEnv.step`.

        Parameters
        ----------
        action : array_like
            As :meth:`DriveIterationEnv.step`'s (already prepared when an outcome is staged).
        """
        staged, self.outcome = self.outcome, None
        if staged is None:
            return self.env.step(action)
        kind, outcome = staged
        if kind != "step":
            raise RuntimeError(f"a staged {kind} was finished by step()")
        return self.env.unwrapped.finish_step(outcome)

    def reset(self, *, seed=None, options=None):
        """See :meth:`DriveIterationEnv.reset`.

        Parameters
        ----------
        seed : int, optional
            As :meth:`DriveIterationEnv.reset`'s (already applied when an outcome is staged).
        options : dict, optional
            As :meth:`DriveIterationEnv.reset`'s (already applied when an outcome is staged).
        """
        staged, self.outcome = self.outcome, None
        if staged is None:
            return self.env.reset(seed=seed, options=options)
        kind, outcome = staged
        if kind != "reset":
            raise RuntimeError(f"a staged {kind} was finished by reset()")
        env = self.env.unwrapped
        done = env.finish_reset(outcome)
        while done is None:  # the drawn target tripped at IT00: a redraw, played on its own
            drive, n = env.pending
            done = env.finish_reset(env._play(drive, n))
        return done


class DriveIterationVectorEnv(SyncVectorEnv):
    """``num_envs`` drive-iteration envs on one rig whose rig runs are batched across threads.

    Results equal ``gymnasium.make_vec(id, num_envs, vectorization_mode="sync")`` bit for bit
    (same seeds, same actions); only the rig runs of a step (and of a reset) are played together
    (:func:`vrig.reconstruction.engine.play_batch`), and the target records of the resetting
    sub-envs are made in one batch (:meth:`~vrig.envs.IterationPhysics.target_records`). A
    sub-env whose drawn target trips at IT00 redraws on its own, as in a single env. ``AutoresetMode.SAME_STEP`` works but its resets
    are played one by one.

    Parameters
    ----------
    num_envs : int
        Number of sub-environments (>= 1).
    rig : str or Rig
        Rig name or rig object (as :class:`DriveIterationEnv`'s); the sub-envs share the rig
        and its identified inverse model.
    max_episode_steps : int
        Iteration budget per episode (each sub-env is wrapped in ``TimeLimit``); default 10.
    threads : int, optional
        Worker threads of the batched rig runs (:meth:`vrig.rigs.MujocoRig.run_batch`);
        default ``min(num_envs, os.cpu_count())``.
    copy : bool
        As :class:`gymnasium.vector.SyncVectorEnv`'s (return copies of the observations).
    autoreset_mode : str or AutoresetMode
        As :class:`gymnasium.vector.SyncVectorEnv`'s (default ``NEXT_STEP``).
    batch_targets : bool
        Make the target records of the resetting sub-envs in one batch (default); False: each
        sub-env makes its own in turn, in the calling thread (the same records: for
        comparison, ``benchmarks.rig_batch``).
    **env_kwargs
        Keyword arguments of every :class:`DriveIterationEnv` (``fast``, ``action_mode``,
        ``n_bands``, ``tolerance``, ``target``, ...); the physics' own
        (:data:`~vrig.envs.drive_iteration.PHYSICS_OPTIONS`: ``target``, ``seconds``, the
        method, ...) build the one shared :class:`~vrig.envs.IterationPhysics`, so every sub-env draws its records from the
        same ``target`` (each reset its own seed).
    """

    def __init__(
        self,
        num_envs: int,
        rig="shock-absorber",
        *,
        max_episode_steps: int = 10,
        threads: int | None = None,
        copy: bool = True,
        autoreset_mode: str | AutoresetMode = AutoresetMode.NEXT_STEP,
        batch_targets: bool = True,
        **env_kwargs,
    ):
        if not isinstance(num_envs, (int, np.integer)) or num_envs < 1:
            raise ValueError(f"num_envs must be a positive integer, got {num_envs!r}")
        if not isinstance(max_episode_steps, (int, np.integer)) or max_episode_steps < 1:
            raise ValueError(
                f"max_episode_steps must be a positive integer, got {max_episode_steps!r}"
            )
        first = DriveIterationEnv(rig, **env_kwargs)
        # one rig and one physics for all: their drives can be batched on that rig
        task_kwargs = {k: v for k, v in env_kwargs.items() if k not in PHYSICS_OPTIONS}
        others = [DriveIterationEnv(first.physics, **task_kwargs) for _ in range(num_envs - 1)]
        self._staged = [_Staged(e) for e in (first, *others)]
        wrapped = [TimeLimit(s, max_episode_steps) for s in self._staged]
        super().__init__(
            [lambda w=w: w for w in wrapped], copy=copy, autoreset_mode=autoreset_mode
        )
        self.max_episode_steps = int(max_episode_steps)
        self.threads = threads if threads is not None else min(num_envs, os.cpu_count() or 1)
        self.batch_targets = bool(batch_targets)

    # ------------------------------------------------------------------ batching
    def _play_staged(self, prepared: dict, kinds: dict) -> None:
        """Play the prepared ``{i: (drive, n)}`` in one batch and stage each outcome (as
        ``(kinds[i], outcome)``: resets' IT00 drives and steps' drives in the same batch)."""
        live = [i for i, (drive, _) in prepared.items() if drive is not None]
        envs = [self._staged[i].unwrapped for i in live]
        outcomes = play_batch(
            [e.engine for e in envs],
            [prepared[i][0] for i in live],
            [prepared[i][1] for i in live],
            threads=self.threads,
        )
        for i in prepared:
            self._staged[i].outcome = (kinds[i], None)
        for i, outcome in zip(live, outcomes, strict=True):
            self._staged[i].outcome = (kinds[i], outcome)

    def _play_prepared(self, steps: dict, resets: dict, kinds: dict) -> None:
        """Prepare the sub-envs: ``steps`` ``{i: action}`` (:meth:`~DriveIterationEnv.
        prepare_step`) and ``resets`` ``{i: (seed, options)}`` (:meth:`~DriveIterationEnv.
        draw_reset`, then the drawn target records of all of them in one batch,
        :meth:`~vrig.envs.IterationPhysics.target_records`, then :meth:`~DriveIterationEnv.
        start_reset`), and play and stage every prepared drive (:meth:`_play_staged`). While
        the target records are made, the steps' drives already play (in a second thread, on
        the rig's other data: every run is seeded, so the outcomes are the same), then the
        resets' IT00 drives. An error (a bad action, say) ends every sub-env's episode - some
        were prepared already, so no consistent batch is left to finish - and goes on:
        ``reset()`` the vector env then."""
        prepared, ahead = {}, None
        try:
            for i, action in steps.items():
                prepared[i] = self._staged[i].unwrapped.prepare_step(action)
            envs = {i: self._staged[i].unwrapped for i in resets}
            drawn = [e.draw_reset(seed=resets[i][0], options=resets[i][1]) for i, e in envs.items()]
            wanted = [s for s in drawn if s is not None]
            if wanted and self.batch_targets:  # each start_reset then finds its record made
                if prepared:  # the steps' runs beside the targets' own
                    ahead = _Ahead(self._play_staged, dict(prepared), kinds)
                    prepared = {}
                self._staged[0].unwrapped.physics.target_records(wanted, threads=self.threads)
            for i, env in envs.items():
                prepared[i] = env.start_reset()
        except BaseException:
            if ahead is not None:
                ahead.wait()  # no run of it is left live
            for staged in self._staged:
                staged.outcome = None
                staged.unwrapped.close()
            raise
        try:
            self._play_staged(dict(sorted(prepared.items())), kinds)
        finally:
            if ahead is not None:
                ahead.finish()

    def step(self, actions):
        """Step every sub-env (resetting those that ended, in ``NEXT_STEP`` mode), their rig
        runs batched (the resetting sub-envs' target records first, then every drive in one
        batch); as :meth:`gymnasium.vector.SyncVectorEnv.step`.

        Parameters
        ----------
        actions : array_like
            A batch of actions (``self.action_space``).
        """
        acts = list(iterate(self.action_space, actions))
        next_step = self.autoreset_mode == AutoresetMode.NEXT_STEP
        kinds = {
            i: "reset" if next_step and self._autoreset_envs[i] else "step"
            for i in range(self.num_envs)
        }
        steps = {i: acts[i] for i, k in kinds.items() if k == "step"}
        resets = {i: (None, None) for i, k in kinds.items() if k == "reset"}
        self._play_prepared(steps, resets, kinds)
        return super().step(actions)

    def reset(self, *, seed=None, options=None):
        """Reset the sub-envs (all, or ``options["reset_mask"]``'s), their IT00 runs batched;
        as :meth:`gymnasium.vector.SyncVectorEnv.reset` (same seeds per sub-env).

        Parameters
        ----------
        seed : int or list of int, optional
            ``seed + i`` for sub-env ``i`` (an int), one per sub-env (a list), or None.
        options : dict, optional
            Reset options of every sub-env, plus ``"reset_mask"`` (bool array, num_envs).
        """
        if seed is None:
            seeds = [None] * self.num_envs
        elif isinstance(seed, (int, np.integer)):
            seeds = [int(seed) + i for i in range(self.num_envs)]
        else:
            seeds = list(seed)
        if len(seeds) != self.num_envs:  # SyncVectorEnv.reset says so, before anything runs
            return super().reset(seed=seed, options=options)
        env_options = {k: v for k, v in (options or {}).items() if k != "reset_mask"}
        mask = (options or {}).get("reset_mask")
        mask = np.ones(self.num_envs, bool) if not isinstance(mask, np.ndarray) else mask

        masked = mask.shape == (self.num_envs,) and mask.dtype == np.bool_
        resets = {
            i: (seeds[i], env_options) for i in range(self.num_envs) if not masked or mask[i]
        }
        self._play_prepared({}, resets, dict.fromkeys(resets, "reset"))
        return super().reset(seed=seed, options=options)


class _Ahead:
    """``fn(*args)`` in a thread of its own, started at once; :meth:`finish` waits for it and
    raises what it raised."""

    def __init__(self, fn, *args):
        self.error = None

        def run():
            try:
                fn(*args)
            except BaseException as exc:  # handed to the calling thread by finish()
                self.error = exc

        self.thread = threading.Thread(target=run, name="vrig-steps-ahead", daemon=True)
        self.thread.start()

    def wait(self) -> None:
        """Wait until the thread has ended (whatever it raised stays unraised)."""
        self.thread.join()

    def finish(self) -> None:
        """Wait until the thread has ended and raise its error, if any."""
        self.wait()
        if self.error is not None:
            raise self.error
