"""Calibrate a virtual rig's documented parameters on ONE observable the reference text reports.

    python -m benchmarks.calibrate elastomeric-damper [--quick] [--write]

Issue 12: the virtual rigs are milder than the real ones the text measured. A twin is
calibrated on the **linear baseline** only — the text's own linear procedure (Table 6.3: inverse
ARX(6), IT00, η0 of ITRES against DESRES on a pseudo-field desired response; quick settings:
20 s desired response, 30 s identification record, seed 0, band 0-25 Hz) must give the text's
57 % within ±25 % relative (43-71 %) — by physically meaningful parameters within their
documented plausible ranges (``models/<rig>/README.md``). What it was *not* calibrated on (the
NARX gain, text: 24 %) is then a prediction: ``--predict`` runs it, never tunes on it.

Search (elastomeric damper): a scalar **progressivity severity** ``s`` multiplies the rubber's
progressive terms together (``quadratic_stiffness`` = asymmetry, ``cubic_stiffness`` =
progressive stiffening / travel-limiter engagement), on a coarse grid over ``s`` and the Iwan
``iwan_slip_scale`` (hysteresis); then bisection in ``log s`` at the grid's slip scale closest to
datasheet-typical that brackets the target. Every evaluation is printed. ``--write`` stores the
result as the side-car variant ``"thesis"`` (atomic write); the default variant is unchanged.
"""

from __future__ import annotations

import argparse
import itertools
import json
import math
import time
from pathlib import Path

__all__ = ["CALIBRATIONS", "calibrate", "evaluate", "predict", "write_variant"]

TARGET = 57.0  # % Table 6.3, QanTiM inverse ARX(6), IT00
TOLERANCE = 0.25  # relative
NARX_TEXT = 24.0  # % Table 6.3, NARX 4th order quadratic (the prediction, never tuned)
SECONDS, ID_SECONDS, BAND = 20.0, 30.0, (0.0, 25.0)  # the quick settings of Table 6.3

CALIBRATIONS = {
    "elastomeric-damper": {
        # severity s scales these together (their datasheet-typical defaults x s)
        "severity": ("quadratic_stiffness", "cubic_stiffness"),
        "grid": [1.0, 3.0, 10.0, 20.0, 40.0],
        "quick_grid": [1.0, 10.0, 30.0],
        "slip": [1.0, 2.0],  # iwan_slip_scale (hysteresis)
        "quick_slip": [1.0],
    }
}


def _linear_baseline(rig) -> float:
    """IT00 η0 [%] of the text's linear procedure on ``rig`` (Table 6.3, quick settings)."""
    import vrig
    from vrig.field import pseudo_field
    from vrig.reconstruction import InverseArx

    _drive, desired = pseudo_field(rig, BAND, SECONDS, seed=0)
    res = vrig.reconstruct(
        rig,
        desired,
        method=InverseArx(6),
        iterations=0,
        bandwidth=BAND,
        id_duration=ID_SECONDS,
        seed=0,
    )
    return float(res.errors[0][0])


def _values(rig_name: str, severity: float, slip: float) -> dict:
    import vrig

    params = vrig.load_rig(rig_name).description.parameters
    cal = CALIBRATIONS[rig_name]
    out = {k: float(params[k].value) * severity for k in cal["severity"]}
    out["iwan_slip_scale"] = float(slip)
    return out


def evaluate(rig_name: str, values: dict, log=print) -> float:
    """The objective (linear-baseline η0, %) for parameter ``values``; NaN if the procedure
    fails (an interlock, a refused value): printed either way."""
    import vrig

    t0 = time.perf_counter()
    try:
        eta = _linear_baseline(vrig.load_rig(rig_name, seed=0, **values))
    except Exception as exc:  # the honest figure is the failure
        eta = float("nan")
        note = f"FAILED {type(exc).__name__}: {str(exc).splitlines()[0][:120]}"
    else:
        note = f"inverse ARX(6) IT00 eta0 = {eta:6.2f} %  (text {TARGET:g} %)"
    shown = ", ".join(f"{k} = {v:.4g}" for k, v in values.items())
    log(f"  {shown}: {note}  [{time.perf_counter() - t0:.1f} s]")
    return eta


def calibrate(rig_name: str, *, quick: bool = False, log=print) -> dict:
    """Coarse grid over (severity, slip scale), then bisection in log(severity).

    Returns a dict: ``values`` (the calibrated parameters), ``objective`` (η0 %), ``severity``,
    ``evaluations`` (every (values, η0) pair) and ``seconds``.
    """
    if rig_name not in CALIBRATIONS:
        raise SystemExit(f"no calibration defined for {rig_name!r}; have {sorted(CALIBRATIONS)}")
    cal = CALIBRATIONS[rig_name]
    t_start = time.perf_counter()
    evals = []

    def f(s, slip):
        values = _values(rig_name, s, slip)
        eta = evaluate(rig_name, values, log)
        evals.append((values, eta))
        return eta

    lo_ok, hi_ok = TARGET * (1 - TOLERANCE), TARGET * (1 + TOLERANCE)
    grid = cal["quick_grid"] if quick else cal["grid"]
    slips = cal["quick_slip"] if quick else cal["slip"]
    log(f"coarse grid: severity {grid} x iwan_slip_scale {slips}")
    table = {slip: [(s, f(s, slip)) for s in grid] for slip in slips}
    bracket = None
    for slip in slips:  # the slip scale closest to datasheet-typical first
        pts = [(s, e) for s, e in table[slip] if math.isfinite(e)]
        for (s0, e0), (s1, e1) in itertools.pairwise(pts):
            if (e0 - TARGET) * (e1 - TARGET) <= 0:
                bracket = (slip, s0, e0, s1, e1)
                break
        if bracket:
            break
    if bracket is None:
        best = min(
            ((v, e) for v, e in evals if math.isfinite(e)),
            key=lambda ve: abs(ve[1] - TARGET),
            default=(None, float("nan")),
        )
        log(f"the grid does not bracket {TARGET:g} %: best {best[1]:.2f} % at {best[0]}")
        values, eta, sev = best[0], best[1], float("nan")
    else:
        slip, s0, e0, s1, e1 = bracket
        log(f"1-D refinement: bisection in log(severity) in [{s0:g}, {s1:g}] at slip {slip:g}")
        best_s, best_e = min(((s0, e0), (s1, e1)), key=lambda se: abs(se[1] - TARGET))
        for _ in range(3 if quick else 5):
            if abs(best_e - TARGET) <= 0.05 * TARGET:  # within ±5 % relative: done
                break
            sm = math.sqrt(s0 * s1)
            em = f(sm, slip)
            if not math.isfinite(em):
                break
            if (e0 - TARGET) * (em - TARGET) <= 0:
                s1, e1 = sm, em
            else:
                s0, e0 = sm, em
            if abs(em - TARGET) < abs(best_e - TARGET):
                best_s, best_e = sm, em
        sev = best_s
        values, eta = _values(rig_name, best_s, slip), best_e
    seconds = time.perf_counter() - t_start
    ok = lo_ok <= eta <= hi_ok
    log(
        f"result: {values} -> inverse ARX(6) IT00 eta0 {eta:.2f} % vs the text's {TARGET:g} % "
        f"({'within' if ok else 'OUTSIDE'} ±{TOLERANCE:.0%}: {lo_ok:.2f}-{hi_ok:.2f} %), "
        f"{len(evals)} evaluations, {seconds:.0f} s"
    )
    return {
        "values": values,
        "objective": eta,
        "severity": sev,
        "ok": ok,
        "evaluations": evals,
        "seconds": seconds,
    }


def predict(rig_name: str, variant: str = "thesis", log=print) -> dict:
    """Table 6.3's NARX rows on the variant (what it was NOT calibrated on), IT00 η0 %."""
    import vrig
    from vrig.field import pseudo_field
    from vrig.reconstruction import InverseNarx

    rig = vrig.load_rig(rig_name, seed=0, variant=variant)
    _drive, desired = pseudo_field(rig, BAND, SECONDS, seed=0)
    rows = {
        "NARX(4, 2) full, simulation focus, SEMP terms": lambda: InverseNarx(
            4, 2, kind="full", focus="simulation", selection="simulation"
        ),
        "NARX(4, 2) input-polynomial": lambda: InverseNarx(4, 2, kind="input-polynomial"),
    }
    out = {}
    for label, method in rows.items():
        t0 = time.perf_counter()
        try:
            res = vrig.reconstruct(
                rig,
                desired,
                method=method(),
                iterations=0,
                bandwidth=BAND,
                id_duration=ID_SECONDS,
                seed=0,
            )
            out[label] = float(res.errors[0][0])
            log(
                f"  {label}: IT00 eta0 {out[label]:.2f} % vs the text's {NARX_TEXT:g} % "
                f"[{time.perf_counter() - t0:.0f} s]"
            )
        except Exception as exc:
            out[label] = f"{type(exc).__name__}: {str(exc).splitlines()[0][:120]}"
            log(f"  {label}: FAILED {out[label]}")
    return out


def _with_variants(original: str, raw: dict) -> str:
    """The side-car text with its ``"variants"`` block (the last key) replaced or appended,
    keeping the hand-written layout of the rest."""
    block = json.dumps(raw["variants"], indent=2, ensure_ascii=False).replace("\n", "\n  ")
    head = original.rstrip()
    cut = head.find('\n  "variants":')
    if cut >= 0:
        head = head[:cut].rstrip().rstrip(",")
    else:
        head = head[: head.rfind("}")].rstrip()
    return f'{head},\n  "variants": {block}\n}}\n'


def write_variant(rig_name: str, result: dict, name: str = "thesis") -> Path:
    """Store ``result`` as the side-car variant ``name`` (validated, atomic write)."""
    from vrig.files import atomic_write
    from vrig.rigs import rig_path
    from vrig.rigs.spec import read_description, validate_description

    path = Path(rig_path(rig_name))
    raw = json.loads(path.read_text())
    v = result["values"]
    desc = (
        f"calibrated (benchmarks/calibrate.py, issue 12) on ONE observable of the reference text: "
        f"Table 6.3's linear baseline, inverse ARX(6) IT00 eta0 = {TARGET:g} %, by the rubber "
        f"progressivity (quadratic_stiffness and cubic_stiffness x {result['severity']:.3g} of "
        f"the datasheet-typical defaults) at iwan_slip_scale {v['iwan_slip_scale']:g}; gives "
        f"{result['objective']:.1f} % (quick settings: 20 s pseudo-field desired response, 30 s "
        f"identification, seed 0, 0-25 Hz). Everything else datasheet-typical. Not tuned on "
        f"the NARX rows (the text's 24 %): see the README."
    )
    raw.setdefault("variants", {})[name] = {
        "description": desc,
        "parameters": {k: float(f"{x:.4g}") for k, x in v.items()},
        "calibration": {
            "observable": "Table 6.3 inverse ARX(6) IT00 eta0 [%], quick settings",
            "target": TARGET,
            "achieved": round(result["objective"], 2),
            "severity": round(result["severity"], 4),
            "evaluations": len(result["evaluations"]),
        },
    }
    validate_description(raw, str(path))
    text = _with_variants(path.read_text(), raw)
    if json.loads(text) != raw:  # the hand layout could not be kept: plain JSON
        text = json.dumps(raw, indent=2, ensure_ascii=False) + "\n"
    check = path.with_name(f".{path.name}.check.json")  # read back before replacing
    try:
        check.write_text(text)
        mjcf = path.parent / raw["mjcf"]
        check_raw = dict(raw, mjcf=str(mjcf.resolve()))
        check.write_text(json.dumps(check_raw))
        read_description(check)
    finally:
        check.unlink(missing_ok=True)
    with atomic_write(path, "w") as fh:
        fh.write(text)
    return path


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(
        prog="python -m benchmarks.calibrate", description=__doc__.split("\n")[0]
    )
    ap.add_argument("rig", choices=sorted(CALIBRATIONS))
    ap.add_argument("--quick", action="store_true", help="a coarser grid, fewer refinements")
    ap.add_argument("--write", action="store_true", help="store the result as variant 'thesis'")
    ap.add_argument(
        "--predict",
        action="store_true",
        help="then run Table 6.3's NARX rows on the 'thesis' variant (not tuned)",
    )
    args = ap.parse_args(argv)
    result = calibrate(args.rig, quick=args.quick)
    if args.write:
        if not result["ok"]:
            print("not written: the result is outside the tolerance")
            return 1
        print(f"written: variant 'thesis' in {write_variant(args.rig, result)}")
    if args.predict:
        print("prediction (NOT calibrated on):")
        predict(args.rig)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
