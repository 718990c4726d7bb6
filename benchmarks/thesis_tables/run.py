"""The thesis tables' run: vrig's figures for each row (the reconstructions, the normal models'
free runs, Table 3.7's modelling errors, the Belgian road example) and the variant and severity
each table runs on."""

from __future__ import annotations

import time
from typing import NamedTuple

import numpy as np

from benchmarks.thesis_tables.data import NOT_IN_QUICK, NormalRow, NormalTable, Table

__all__ = [
    "TableRun",
    "belgian_road_example",
    "normal_records",
    "resolve_severity",
    "resolve_variant",
    "run_normal_table",
    "run_table",
    "table_3_7",
]


def resolve_variant(rig_name: str, requested: str | None) -> str:
    """The variant a table on ``rig_name`` runs on for ``--variant requested``: ``requested``
    where the rig has it, else the rig's default variant (``None``: the default)."""
    from vrig.rigs import rig_path
    from vrig.rigs.spec import read_description

    desc = read_description(rig_path(rig_name))
    return requested if requested in desc.variants else desc.default_variant


def resolve_severity(rig_name: str, severity: float | None) -> float | None:
    """``severity`` for a rig with a severity axis, ``None`` (as loaded) for a linear rig."""
    import vrig

    if severity is None or rig_name not in vrig.severity_rigs():
        return None
    return float(severity)


def _setting(rig_name: str, requested: str | None, severity: float | None) -> tuple:
    """(variant, severity) a table on ``rig_name`` runs on."""
    return resolve_variant(rig_name, requested), resolve_severity(rig_name, severity)


def _desired(rig, band, seconds, cache, target: str = "pseudo-field"):
    """The table's desired response on ``rig`` (cached): ``target`` made by
    :func:`vrig.desired.kinds.desired_response` (a pseudo-field record over ``band``, or a service
    record of the rig's field twin)."""
    from vrig.desired.kinds import desired_response

    key = (rig.name, getattr(rig, "variant", None), getattr(rig, "severity", None), band,
           seconds, target)  # fmt: skip
    if key not in cache:
        cache[key] = desired_response(rig, target, seconds, seed=0, band=band)[0]
    return cache[key]


_SHARED = "; fit shared with the run on the other target: same identification records"


def run_table(
    table: Table,
    *,
    seconds: float,
    id_seconds: float,
    cache: dict,
    variant: str | None = None,
    severity: float | None = None,
    target: str = "pseudo-field",
    quick: bool = False,
    log=print,
):
    """vrig's figures for one table: a list (per row) of per-channel values or an error string.

    ``quick``: the rows with :attr:`Row.quick` False are not run; their value is
    :data:`NOT_IN_QUICK`.

    ``variant``/``severity``: as resolved by :func:`resolve_variant`/:func:`resolve_severity`
    (``None``: the rig's default, as loaded). ``target``: the desired response's kind
    (:func:`vrig.desired.kinds.desired_response`: ``"pseudo-field"`` or ``"field:<scenario>"``).
    ``cache``: the desired responses and, under ``"fits"``, the rows' inverse fits, shared
    between the runs of a row on the same identification records
    (:class:`~benchmarks.shared_fits.SharedFit`: the default identification does not depend on
    the target, so a row's pseudo-field run reuses its field run's fit; an ``id_match`` row
    fits again)."""
    import vrig
    from benchmarks.shared_fits import SharedFit

    rig = vrig.load_rig(table.rig, seed=0, variant=variant, severity=severity)
    try:
        desired = _desired(rig, table.band, seconds, cache, target)
    except Exception as exc:  # the honest figure is the failure, for every row
        why = f"no {target} target: {type(exc).__name__}: {str(exc).splitlines()[0][:160]}"
        log(f"  {why}")
        return [why] * len(table.rows)
    runs, values, fits = {}, [], cache.setdefault("fits", {})
    for row in table.rows:
        if quick and not row.quick:
            values.append(NOT_IN_QUICK)
            continue
        key = row.key or row.label
        if key not in runs:
            iterations = max(r.iteration for r in table.rows if (r.key or r.label) == key)
            t0 = time.perf_counter()
            method = SharedFit(row.method(), (table.name, key, variant, severity), fits)
            try:
                runs[key] = vrig.reconstruct(
                    rig,
                    desired,
                    method=method,
                    iterations=iterations,
                    bandwidth=table.band,
                    id_duration=id_seconds,
                    seed=0,
                    **row.options,  # e.g. id_match: the identification matched to the target
                )
                log(
                    f"  {row.label}: {runs[key].method.describe()} ({time.perf_counter() - t0:.0f} s"
                    f"{_SHARED if method.shared else ''})"
                )
            except Exception as exc:  # the honest figure is the failure
                runs[key] = f"{type(exc).__name__}: {str(exc).splitlines()[0][:160]}"
                log(
                    f"  {row.label}: FAILED {runs[key]} ({time.perf_counter() - t0:.0f} s"
                    f"{_SHARED if method.shared else ''})"
                )
        res = runs[key]
        if isinstance(res, str):
            values.append(res)
        elif row.iteration >= len(res.errors):
            values.append(f"stopped before IT{row.iteration:02d}: {res.stopped[:120]}")
        else:
            idx = [list(res.desired.names).index(c) for c in table.channels]
            values.append([float(res.errors[row.iteration][i]) for i in idx])
    return values


def _rest_values(rig, names) -> np.ndarray:
    """Each channel's value at rest: the mean of the last second of a 3 s zero drive."""
    from vrig.timehistory import TimeHistory

    n = round(3.0 * rig.fs)
    zero = TimeHistory(
        np.zeros((n, len(rig.inputs))), rig.fs, [c.name for c in rig.inputs],
        [c.unit for c in rig.inputs],
    )  # fmt: skip
    y = rig.run(zero, seed=0)
    rest = {c.name: 0.0 for c in rig.inputs}
    rest.update({c: float(y[c].data[-round(rig.fs) :].mean()) for c in y.names})
    return np.array([rest[c] for c in names])


def normal_records(rig, table: NormalTable, *, seconds: float, level: float, log=print):
    """The identification record (seed 1) and the held-out record (seed 2) of ``table``: an
    identification-type random drive (triangular PSD over the identification band, the band
    widened by 20 %, as ``vrig.reconstruct`` identifies) at ``level`` x each drive's full scale
    RMS, halved (up to three times) while the rig trips. Returns ``((u1, y1), (u2, y2)), fs,
    rms`` at the model rate, each channel's value at rest removed."""
    from vrig.errors import RigLimitError
    from vrig.processing import decimate, gprepro, identification_band
    from vrig.signals import random_drive, triangular_psd
    from vrig.timehistory import TimeHistory

    id_band = identification_band(table.band, fs=rig.fs)
    dec = max(1, int(rig.fs // (8 * id_band[1])))
    names = [c.name for c in rig.inputs]
    full = np.array([c.full_scale for c in rig.inputs])
    n = round(seconds * rig.fs)
    cols = list(table.inputs) + list(table.channels)
    rest = _rest_values(rig, cols)
    rms = level * full
    for _attempt in range(4):
        try:
            recs = []
            for seed in (1, 2):
                u = random_drive(
                    triangular_psd((0.0, id_band[1])), n, rig.fs, channels=len(names), rms=rms,
                    seed=seed, names=names, unit=rig.inputs[0].unit,
                )  # fmt: skip
                y = rig.run(u, seed=seed)
                both = {
                    **{c: u[c].data[:, 0] for c in names},
                    **{c: y[c].data[:, 0] for c in y.names},
                }
                x = np.column_stack([both[c] for c in cols]) - rest
                th = TimeHistory(x, rig.fs, cols)
                x = decimate(gprepro(th, table.band, detrend=False, remove_dc=False), dec).data
                k = len(table.inputs)
                recs.append((x[:, :k], x[:, k:]))
            return recs, rig.fs / dec, rms
        except RigLimitError as exc:
            log(f"  {str(exc).splitlines()[0][:120]}: halving the drive RMS")
            rms = rms / 2
    raise RigLimitError(f"{rig.name}: the identification drive trips even at 1/8 of {level:.0%} FS")


def _fit_simulate(row: NormalRow, fs: float, u1, y1, u2):
    """Fit ``row``'s model on (u1, y1) and free-run it on u2; with ``row.refocus`` a model whose
    least-squares free run diverges (``UnstableModelError``) is refitted with the simulation
    focus. Returns (simulation, refocused?)."""
    from identification import UnstableModelError

    model = row.model(fs)
    try:
        model.fit(u1, y1)
        refocused = False
    except UnstableModelError:
        if not row.refocus:
            raise
        model = _refocus(model)
        model.fit(u1, y1)
        refocused = True
    return model.simulate(u2), refocused


def _refocus(model):
    """The same model with every least-squares part switched to ``focus="simulation"``."""
    import copy

    from identification import ErrorSignalModel, Narx, SplitSpectraModel

    model = copy.deepcopy(model)
    parts = [model]
    if isinstance(model, ErrorSignalModel):
        parts += [model.linear, model.nonlinear]
    elif isinstance(model, SplitSpectraModel):
        parts += [model.low, model.high]
    for m in parts:
        if isinstance(m, Narx):
            m.focus = "simulation"
    return model


def run_normal_table(table: NormalTable, *, seconds: float, level: float, variant=None,
                     severity=None, log=print):  # fmt: skip
    """vrig's figures for one normal table at one drive level: (values, notes, rms) with values
    a list (per row) of per-channel η0 [%] (or an error string) and notes per row ("simulation
    focus" where least squares diverged)."""
    import vrig
    from identification.metrics import qantim_fit_dc

    rig = vrig.load_rig(table.rig, seed=0, variant=variant, severity=severity)
    try:
        ((u1, y1), (u2, y2)), fs, rms = normal_records(
            rig, table, seconds=seconds, level=level, log=log
        )
    except Exception as exc:
        msg = f"{type(exc).__name__}: {str(exc).splitlines()[0][:160]}"
        return [msg] * len(table.rows), [""] * len(table.rows), "-"
    rms_text = ", ".join(f"{r:.3g} {c.unit}" for r, c in zip(rms, rig.inputs, strict=True))
    values, notes = [], []
    for row in table.rows:
        t0 = time.perf_counter()
        try:
            sim, refocused = _fit_simulate(row, fs, u1, y1, u2)
            if not np.all(np.isfinite(sim)):
                raise FloatingPointError("the free run on the held-out record is not finite")
            values.append([float(e) for e in qantim_fit_dc(y2, sim)])
            notes.append("simulation focus" if refocused else "")
            log(f"  {row.label} @ {level:.0%} FS: {np.round(values[-1], 1).tolist()} %"
                f"{' (simulation focus)' if refocused else ''} ({time.perf_counter() - t0:.0f} s)")  # fmt: skip
        except Exception as exc:  # the honest figure is the failure
            values.append(f"{type(exc).__name__}: {str(exc).splitlines()[0][:160]}")
            notes.append("")
            log(f"  {row.label} @ {level:.0%} FS: FAILED {values[-1]} "
                f"({time.perf_counter() - t0:.0f} s)")  # fmt: skip
    return values, notes, rms_text


class TableRun(NamedTuple):
    """One run of a :class:`Table`: a column of its report."""

    name: str  # the column's name: "variant, target"
    setting: str  # the variant (and severity) in words, with the target
    values: list  # per row: per-channel η0 [%], or why the procedure failed (a string)
    variant: str  # the calibrated verdict's variant ("thesis on field:..." on a field target)
    target: str  # the desired response's kind (vrig.desired.kinds.desired_response)


def table_3_7(*, seconds: float, order: int = 4, variant: str | None = None, log=print):
    """Table 3.7: modelling error per channel, rig-specific (Algorithm 3.1) vs triangular PSD.

    A 0-40 Hz linear sine sweep at 0.015" (0.38 mm) is played through each actuator in turn
    (the text's procedure); Algorithm 3.1 turns each actuator's sweep drive/response PSDs into
    its identification PSD. Both identification drives have the same RMS per channel (5 % of
    full scale) and the 1-40 Hz band. The modelling error is the η0 [%] of the inverse ARX
    model's free-run drive on a held-out record of the same PSD (another seed).
    """
    import vrig
    from identification import Arx, InverseModel
    from identification.metrics import qantim_fit_dc
    from vrig.processing import decimate, gprepro
    from vrig.signals import random_drive, rig_specific_psd, sine_sweep, triangular_psd
    from vrig.timehistory import TimeHistory

    rig = vrig.load_rig("fuel-tank-7ch", seed=0, variant=variant)
    band, fs, n_in = (1.0, 40.0), rig.fs, len(rig.inputs)
    names = [c.name for c in rig.inputs]
    sweep = sine_sweep(0.5, 40.0, 20.0, fs, amplitude=0.015 * 0.0254).data[:, 0]
    drv = np.zeros((sweep.size, n_in))
    res = np.zeros((sweep.size, n_in))
    for k in range(n_in):  # one actuator at a time; response k pairs with drive k
        d = np.zeros((sweep.size, n_in))
        d[:, k] = sweep
        drv[:, k] = sweep
        res[:, k] = rig.run(TimeHistory(d, fs, names, [c.unit for c in rig.inputs]), seed=k).data[
            :, k
        ]
    specific = rig_specific_psd(
        TimeHistory(drv, fs, names), TimeHistory(res, fs, [c.name for c in rig.outputs])
    )

    def band_mask(shape):  # the rig-specific shape inside the 1-40 Hz band only
        return lambda f: np.where((f >= band[0]) & (f <= band[1]), shape(f), 0.0)

    shapes = {
        "triangular": [triangular_psd(band)] * n_in,
        "rig-specific (Alg. 3.1)": [band_mask(s) for s in specific],
    }
    n = round(seconds * fs)
    dec = max(1, int(fs // (8 * band[1] * 1.2)))

    def records(psd, rms):
        recs = []
        for seed in (1, 2):  # identification, validation
            u = random_drive(psd, n, fs, channels=n_in, rms=rms, seed=seed, names=names, unit="m")
            y = rig.run(u, seed=seed)
            recs.append(
                (decimate(gprepro(u, band), dec).data, decimate(gprepro(y, band), dec).data)
            )
        return recs

    # same RMS for both PSDs: the default identification level, halved (for both) while either
    # trips the rig
    from vrig.reconstruction.defaults import default_id_rms

    rms = default_id_rms(rig)
    for _attempt in range(5):
        try:
            data = {label: records(psd, rms) for label, psd in shapes.items()}
            break
        except vrig.RigLimitError as exc:
            log(f"  {exc}: halving the identification RMS")
            rms = rms / 2
    else:
        return names, {label: "the rig trips even at 1/32 of 5 % full scale" for label in shapes}
    log(f"  identification RMS {', '.join(f'{1e3 * r:.2f}' for r in rms)} mm")
    out = {}
    for label, ((u_id, y_id), (u_val, y_val)) in data.items():
        inv = InverseModel(Arx(order=order)).fit(u_id, y_id)
        try:
            out[label] = qantim_fit_dc(u_val, inv.simulate(y_val, bound=np.inf)).tolist()
        except Exception as exc:
            out[label] = f"{type(exc).__name__}: {str(exc)[:120]}"
        fwd = Arx(order=order).fit(u_id, y_id)  # the normal model: responses from drives
        try:
            out[label + " normal"] = qantim_fit_dc(
                y_val, fwd.simulate(u_val, bound=np.inf)
            ).tolist()
        except Exception as exc:
            out[label + " normal"] = f"{type(exc).__name__}: {str(exc)[:120]}"
        log(f"  {label}: lead {inv.lead_}, contraction {inv.contraction_:.4f}")
    return [c.name for c in rig.inputs], out


def belgian_road_example(
    *,
    seconds: float,
    iterations: int = 3,
    variant: str | None = None,
    log=print,
) -> str:
    """The Belgian-block road record (real wheel accelerations, 256 Hz) as the desired response
    of the seven-channel fuel-tank rig: Table 3.7's rig on the text's kind of target (a road
    simulation).

    F2D by :func:`vrig.desired.belgian_block.belgian_block_desired` (the one place it is done: the four outer
    wheels to the four vertical accelerations, 256 -> 250 Hz, band 1-40 Hz, 5 s skipped, one
    common scale so the best linear drive needs at most half of every actuator limit); the
    inverse is built on the four vertical responses (:func:`vrig.desired.belgian_block.belgian_block_rig`: 7
    drives from 4 responses); the lateral and longitudinal responses are not controlled and not
    scored.
    """
    import vrig
    from vrig.desired.belgian_block import (
        belgian_block_desired,
        belgian_block_path,
        belgian_block_rig,
    )

    try:
        path = belgian_block_path()
    except FileNotFoundError as exc:
        return f"Belgian road example skipped: {exc}\n"
    full = vrig.load_rig("fuel-tank-7ch", seed=0, variant=variant)
    rig = belgian_block_rig(full)
    band = (1.0, 40.0)
    try:
        desired = belgian_block_desired(rig, path, seconds=seconds)
        res = vrig.reconstruct(
            rig, desired, method="arx", iterations=iterations, bandwidth=band, seed=0
        )
    except Exception as exc:
        return f"Belgian road example failed: {type(exc).__name__}: {exc}\n"
    log(res.table())
    rms = np.sqrt(np.mean(np.asarray(desired.data) ** 2, axis=0))
    return (
        "### Belgian-block road record on the seven-channel fuel tank (ARX, 1-40 Hz)\n\n"
        f"rig `fuel-tank-7ch`, variant {full.variant!r}; "
        f"{seconds:g} s of the four outer wheel accelerations (vrig.desired.belgian_block.belgian_block_desired: "
        f"scaled so the best linear drive needs at most half of every actuator limit; "
        f"{', '.join(f'{v:.2f}' for v in rms)} m/s² RMS)\n\n"
        "```\n" + res.table() + f"\n```\n{('stopped: ' + res.stopped) if res.stopped else ''}\n"
    )
