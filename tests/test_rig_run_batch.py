"""Batched rig runs (issue 16, deliverable 2): ``MujocoRig.run_batch``, ``vrig.rigs.run_batch``
and the engine's ``play_batch`` give, drive by drive, exactly what one-at-a-time runs give.

The truth here is the rig's own single ``run`` (and the engine's own ``play``) on an identically
loaded twin: every result is compared bit for bit, errors by type and message, and the
``rejected`` bookkeeping of the engine by record name and drive. Drives are short (1.5 s) and
the rigs fast fidelity, so the whole file stays quick.
"""

from __future__ import annotations

import _thread

import numpy as np
import pytest

import vrig
from identification import band_limited_noise
from vrig.reconstruction.engine import DriveIteration, play_batch
from vrig.rigs import OutputSubset, gas_spring, hydraulics, run_batch
from vrig.rigs.mujoco_rig import MAX_BATCH_THREADS

SECONDS = 1.5


def load(name, seed=7):
    return vrig.load_rig(name, seed=seed, fidelity="fast")


def drive(rig, seed, fraction=0.03, seconds=SECONDS):
    """A band-limited random drive in the rig's band at ``fraction`` of full scale."""
    cutoff = min(max(rig.bandwidth[1], 5.0), 0.4 * rig.fs) / (rig.fs / 2)
    d = band_limited_noise(int(seconds * rig.fs), len(rig.inputs), cutoff=cutoff, seed=seed)
    return d * fraction * np.array([c.full_scale for c in rig.inputs])


def tripping(rig):
    """A drive within full scale that trips the following-error interlock mid-run: 0.5 s of a
    small random drive, then a 30 Hz sine of 60 % of full scale, which demands
    0.6 * 0.05 m * 2 pi 30 Hz = 5.7 m/s, ten times the valve's 0.525 m/s velocity limit (side-car
    limits), so the piston falls behind by far more than the 10 mm interlock."""
    x = drive(rig, 99)
    t = np.arange(x.shape[0]) / rig.fs
    on = t >= 0.5
    x[on] = 0.6 * rig.inputs[0].full_scale * np.sin(2 * np.pi * 30 * (t[on] - 0.5))[:, None]
    return x


def beyond(rig):
    """A drive with one sample beyond the first channel's full scale (refused, never sent)."""
    x = drive(rig, 98)
    x[10, 0] = 1.5 * rig.inputs[0].full_scale
    return x


def no_live_context():
    hooks = (hydraulics.CONTROL, gas_spring.PASSIVE, gas_spring.SENSOR)
    return all(not h._live and not h.installed for h in hooks)


def outcome(rig, x, **kw):
    """``rig.run(x)``'s response data, or its exception."""
    try:
        return rig.run(x, **kw).data
    except Exception as exc:
        return exc


def same(got, ref):
    """A batch slot equals a single run's outcome: bit for bit, or the same error."""
    if isinstance(ref, Exception):
        return type(got) is type(ref) and str(got) == str(ref)
    return not isinstance(got, Exception) and np.array_equal(got.data, ref)


@pytest.mark.parametrize("name", ["shock-absorber", "fuel-tank-2ch"])
@pytest.mark.parametrize("threads", [1, 2, 3])
def test_a_batch_is_each_drives_single_run_bit_for_bit_with_explicit_seeds(name, threads):
    rig, twin = load(name), load(name)
    xs = [drive(rig, s) for s in range(5)]  # more drives than threads
    seeds = [11, 3, 11, 40, 5]  # a seed twice: the same response twice
    got = rig.run_batch(xs, seeds=seeds, threads=threads, chunk_seconds=0.5)
    ref = [twin.run(x, seed=s, chunk_seconds=0.5).data for x, s in zip(xs, seeds, strict=True)]
    assert len(got) == len(xs)
    assert all(np.array_equal(g.data, r) for g, r in zip(got, ref, strict=True))
    assert np.array_equal(got[0].data, got[2].data) is np.array_equal(xs[0], xs[2])
    assert got[0].names == twin.run(xs[0], seed=1).names
    assert no_live_context()


@pytest.mark.parametrize("threads", [2, 3])
def test_without_seeds_each_drive_takes_the_rigs_next_stream_in_order(threads):
    rig, twin = load("fuel-tank-2ch", seed=3), load("fuel-tank-2ch", seed=3)
    xs = [drive(rig, s) for s in range(4)]
    got = rig.run_batch(xs, threads=threads)
    ref = [twin.run(x).data for x in xs]  # successive runs: successive streams
    assert all(np.array_equal(g.data, r) for g, r in zip(got, ref, strict=True))
    # both generators have moved on by the same four streams
    assert np.array_equal(rig.run(xs[0]).data, twin.run(xs[0]).data)


def test_refused_drives_are_errors_in_their_slots_and_take_no_stream():
    rig, twin = load("shock-absorber"), load("shock-absorber")
    bad_shape = np.zeros((int(SECONDS * rig.fs), 2))
    nan = drive(rig, 5)
    nan[3, 0] = np.nan
    xs = [drive(rig, 1), beyond(rig), nan, bad_shape, drive(rig, 2)]
    got = rig.run_batch(xs, threads=2, return_exceptions=True)
    ref = [outcome(twin, x) for x in xs]  # one after another, seeds from the generator
    assert isinstance(ref[1], vrig.RigLimitError) and isinstance(ref[3], ValueError)
    assert all(same(g, r) for g, r in zip(got, ref, strict=True))
    assert no_live_context()


@pytest.mark.parametrize("threads", [1, 2])
def test_a_drive_that_trips_mid_run_gives_runs_error_and_the_others_their_responses(threads):
    rig, twin = load("shock-absorber"), load("shock-absorber")
    xs = [drive(rig, 1), tripping(rig), drive(rig, 2), drive(rig, 3)]
    seeds = [1, 2, 3, 4]
    got = rig.run_batch(xs, seeds=seeds, threads=threads, return_exceptions=True)
    ref = [outcome(twin, x, seed=s) for x, s in zip(xs, seeds, strict=True)]
    assert isinstance(ref[1], vrig.RigLimitError) and ref[1].kind == "following error"
    assert ref[1].time > 0.5 - 1 / rig.fs  # it tripped when the sine began, not before
    assert all(same(g, r) for g, r in zip(got, ref, strict=True))
    assert no_live_context()


def test_without_return_exceptions_the_lowest_failing_index_is_raised_after_all_ran():
    rig, twin = load("shock-absorber"), load("shock-absorber")
    # drive 2 is refused before anything runs; drive 1 trips during its run: 1 comes first
    xs = [drive(rig, 1), tripping(rig), beyond(rig), drive(rig, 2)]
    with pytest.raises(vrig.RigLimitError) as err:
        rig.run_batch(xs, threads=2)
    assert err.value.kind == "following error"
    # every valid drive was played: the generator gave three streams, as three runs take
    for x in (xs[0], xs[1], xs[3]):
        outcome(twin, x)
    assert np.array_equal(rig.run(xs[0]).data, twin.run(xs[0]).data)
    assert no_live_context()


def test_an_error_inside_a_worker_removes_every_context():
    rig = load("shock-absorber")
    check = rig._check_stability

    def interrupted(g0, raw, d=None):
        check(g0, raw, d)
        if d is not None and d is rig._clones[0]:
            raise KeyboardInterrupt  # e.g. a Ctrl-C that a worker saw
    rig._check_stability = interrupted
    xs = [drive(rig, s) for s in range(4)]
    with pytest.raises(KeyboardInterrupt):
        rig.run_batch(xs, seeds=[1, 2, 3, 4], threads=2, chunk_seconds=0.25)
    assert no_live_context()


def test_a_ctrl_c_in_the_calling_thread_stops_the_workers_and_removes_every_context():
    rig = load("shock-absorber")
    check, sent = rig._check_stability, []

    def interrupt_once(g0, raw, d=None):
        check(g0, raw, d)
        if not sent:
            sent.append(1)
            _thread.interrupt_main()  # KeyboardInterrupt in the thread waiting for the batch
    rig._check_stability = interrupt_once
    xs = [drive(rig, s, seconds=3.0) for s in range(6)]
    with pytest.raises(KeyboardInterrupt):
        rig.run_batch(xs, seeds=list(range(6)), threads=2, chunk_seconds=0.1)
    assert no_live_context()
    rig._check_stability = check  # and the rig still runs as before
    assert np.array_equal(rig.run_batch(xs[:1], seeds=[0])[0].data, rig.run(xs[0], seed=0).data)


def test_clones_are_made_once_and_kept():
    rig = load("shock-absorber")
    xs = [drive(rig, s) for s in range(3)]
    rig.run_batch(xs, threads=3)
    clones = list(rig._clones)
    assert len(clones) == 2
    rig.run_batch(xs, threads=2)
    assert rig._clones == clones and all(a is b for a, b in zip(rig._clones, clones, strict=True))


@pytest.mark.parametrize(
    "options",
    [{"threads": 0}, {"threads": MAX_BATCH_THREADS + 1}, {"threads": True}, {"threads": 1.5},
     {"seeds": [1, 2]}, {"seeds": [1, -2, 3]}, {"seeds": [1, 2.0, 3]}, {"chunk_seconds": 0}],
)  # fmt: skip
def test_bad_options_are_refused_before_anything_runs(options):
    rig = load("shock-absorber", seed=1)
    twin = load("shock-absorber", seed=1)
    xs = [drive(rig, s) for s in range(3)]
    with pytest.raises(ValueError):
        rig.run_batch(xs, **options)
    assert np.array_equal(rig.run(xs[0]).data, twin.run(xs[0]).data)  # no stream was taken


def test_an_empty_batch_is_an_empty_list():
    assert load("shock-absorber").run_batch([]) == []


class _OneAtATime:
    """A user's rig without run_batch (it only runs)."""

    def __init__(self, rig):
        self._rig = rig
        self.name, self.fs, self.inputs, self.outputs = rig.name, rig.fs, rig.inputs, rig.outputs
        self.bandwidth = rig.bandwidth

    def run(self, drive, *, seed=None):
        return self._rig.run(drive, seed=seed)


def test_the_module_function_batches_a_subset_and_runs_a_plain_rig_one_after_another():
    rig, twin = load("fuel-tank-2ch"), load("fuel-tank-2ch")
    names = [rig.outputs[-1].name]
    xs = [drive(rig, s) for s in range(3)] + [beyond(rig)]
    seeds = [4, 5, 6, 7]
    ref = [outcome(OutputSubset(twin, names), x, seed=s) for x, s in zip(xs, seeds, strict=True)]
    got = run_batch(OutputSubset(rig, names), xs, seeds=seeds, threads=2, return_exceptions=True)
    assert all(same(g, r) for g, r in zip(got, ref, strict=True))
    assert list(got[0].names) == names
    whole = [outcome(twin, x, seed=s) for x, s in zip(xs, seeds, strict=True)]
    got = run_batch(_OneAtATime(rig), xs, seeds=seeds, return_exceptions=True)
    assert all(same(g, r) for g, r in zip(got, whole, strict=True))
    with pytest.raises(vrig.RigLimitError):
        run_batch(_OneAtATime(rig), xs, seeds=seeds)


def _engines(rig, n):
    """``n`` engines on ``rig``, each its own desired response (a response of the rig) and run
    seed; ``play`` needs no identification."""
    out = []
    for k in range(n):
        desired = load("shock-absorber", seed=50 + k).run(drive(rig, 60 + k, 0.05), seed=k)
        out.append(DriveIteration(rig, desired, run_seed=100 + 7 * k))
    return out


def _same_play(got, ref):
    if isinstance(ref, Exception):
        return type(got) is type(ref) and str(got) == str(ref)
    (gd, graw, gres, gsc), (rd, rraw, rres, rsc) = got, ref
    return (
        np.array_equal(gd.data, rd.data) and np.array_equal(graw.data, rraw.data)
        and np.array_equal(gres.data, rres.data)
        and all(np.array_equal(a, b) for a, b in zip(gsc, rsc, strict=True))
    )  # fmt: skip


def test_play_batch_is_each_engines_play_bit_for_bit_with_the_rejected_bookkeeping():
    rig, twin = load("shock-absorber"), load("shock-absorber")
    batch, single = _engines(rig, 5), _engines(twin, 5)
    xs = [drive(rig, 1), beyond(rig), tripping(rig), drive(rig, 2), drive(rig, 3)]
    its = [0, 1, 2, 3, 0]
    for e in batch:
        e.rejected = ("TRIPPED00", None)  # stale bookkeeping that play clears
    ref = []
    for e, x, it in zip(single, xs, its, strict=True):
        try:
            ref.append(e.play(x, it))
        except (vrig.RigLimitError, vrig.errors.SimulationInstabilityError) as exc:
            ref.append(exc)
    got = play_batch(batch, xs, its, threads=2)
    assert isinstance(ref[1], vrig.RigLimitError) and isinstance(ref[2], vrig.RigLimitError)
    assert all(_same_play(g, r) for g, r in zip(got, ref, strict=True))
    for b, s in zip(batch, single, strict=True):
        assert (b.rejected is None) == (s.rejected is None)
        if s.rejected is not None:
            assert b.rejected[0] == s.rejected[0]
            assert np.array_equal(b.rejected[1].data, s.rejected[1].data)
    assert [s.rejected and s.rejected[0] for s in single] == [None, "REFUSED01", "TRIPPED02",
                                                              None, None]  # fmt: skip
    assert no_live_context()


def test_play_batch_refuses_engines_on_different_rigs_and_mismatched_lengths():
    a, b = load("shock-absorber"), load("shock-absorber")
    (ea,), (eb,) = _engines(a, 1), _engines(b, 1)
    with pytest.raises(ValueError, match="same rig"):
        play_batch([ea, eb], [drive(a, 1), drive(a, 2)], 0)
    with pytest.raises(ValueError, match="one drive and one iteration"):
        play_batch([ea], [drive(a, 1), drive(a, 2)], 0)


@pytest.mark.parametrize("threads", [1, 2])
def test_then_runs_on_each_played_response_in_a_worker_and_its_value_takes_the_slot(threads):
    import threading

    rig, twin = load("shock-absorber"), load("shock-absorber")
    xs = [drive(rig, 1), tripping(rig), drive(rig, 2), drive(rig, 3)]
    seeds = [4, 5, 6, 7]
    ref = [outcome(twin, x, seed=s) for x, s in zip(xs, seeds, strict=True)]
    seen = []

    def then(i, response):
        seen.append((i, threading.current_thread() is threading.main_thread()))
        if i == 3:
            raise ZeroDivisionError("then of drive 3")
        return i, response

    got = rig.run_batch(xs, seeds=seeds, threads=threads, return_exceptions=True, then=then)
    assert sorted(i for i, _ in seen) == [0, 2, 3]  # not for the drive that tripped
    assert all(main == (threads == 1) for _, main in seen)  # the workers call it
    assert same(got[1], ref[1]) and isinstance(got[3], ZeroDivisionError)
    for k in (0, 2):
        assert got[k][0] == k and same(got[k][1], ref[k])
    subset = OutputSubset(rig, [rig.outputs[0].name])
    via = run_batch(subset, xs[:1], seeds=seeds[:1], then=lambda i, r: r.names)
    assert via == [(rig.outputs[0].name,)]
    plain = run_batch(_OneAtATime(rig), xs, seeds=seeds, return_exceptions=True, then=then)
    assert same(plain[1], ref[1]) and isinstance(plain[3], ZeroDivisionError)
    assert plain[2][0] == 2 and same(plain[2][1], ref[2])
    with pytest.raises(TypeError, match="callable"):
        rig.run_batch(xs, then=3)
    assert no_live_context()


def test_play_batch_with_one_engine_twice_processes_in_order_after_the_batch():
    rig, twin = load("shock-absorber"), load("shock-absorber")
    (engine,), (single,) = _engines(rig, 1), _engines(twin, 1)
    xs = [drive(rig, 1), drive(rig, 2)]
    ref = [single.play(x, it) for x, it in zip(xs, [1, 2], strict=True)]
    got = play_batch([engine, engine], xs, [1, 2], threads=2)
    assert all(_same_play(g, r) for g, r in zip(got, ref, strict=True))


def test_calls_overlapping_from_two_threads_each_play_on_their_own_data():
    import threading

    rig, twin = load("shock-absorber"), load("shock-absorber")
    xs = [drive(rig, s, seconds=3.0) for s in range(5)]
    ref = [outcome(twin, x, seed=s) for s, x in enumerate(xs)]
    got = {}
    batch = threading.Thread(
        target=lambda: got.update(batch=rig.run_batch(xs[:3], seeds=[0, 1, 2], threads=2))
    )
    batch.start()
    got["run"] = [rig.run(xs[3], seed=3), rig.run_batch(xs[4:], seeds=[4], threads=1)[0]]
    batch.join()
    assert all(same(g, r) for g, r in zip(got["batch"] + got["run"], ref, strict=True))
    assert no_live_context() and not rig._busy  # every data handed back
