"""``vrig reconstruct``'s arguments: the parser of the command (:mod:`vrig.cli` runs it), its
method names (the vocabulary's) and its defaults (:mod:`vrig.reconstruction.defaults` and
:class:`~vrig.reconstruction.IterationSettings`: imported, never retyped)."""

from __future__ import annotations

from ..reconstruction.defaults import DEFAULT_GAIN
from ..reconstruction.settings import STRATEGIES, UPDATES, IterationSettings
from ..reconstruction.vocabulary import BUILTIN_METHODS, RATTLESNAKE_PREFIX
from .common import add_band_argument, add_rig_argument, add_seed_argument


class _MethodChoices(tuple):
    """``--method``'s choices: the built-in names (listed in the help and the error), and any
    ``rattlesnake:FILE.py:NAME`` (:func:`vrig.reconstruction.vocabulary.is_method_name`)."""

    def __contains__(self, value) -> bool:
        return super().__contains__(value) or (
            isinstance(value, str) and value.startswith(RATTLESNAKE_PREFIX)
        )


METHODS = _MethodChoices(BUILTIN_METHODS)
ITERATIONS = IterationSettings.iterations  # the one default (vrig.reconstruct's too)


def _add_parser(sub, epilog: str) -> None:
    """Add the `reconstruct` subcommand: drive iteration on a rig."""
    rec = sub.add_parser(
        "reconstruct",
        help="drive iteration: reproduce a desired response on a rig",
        description="Identify the rig's inverse model, iterate the drive towards the desired "
        "response, print the per-iteration error table and write the QanTiM test folder and "
        "plots. Without --desired the desired response is a pseudo-field response: the rig's "
        "response to a road-like random drive (triangular PSD over the simulation band).",
        epilog=epilog,
    )
    add_rig_argument(rec)
    add_model_arguments(rec)
    rec.add_argument(
        "--desired",
        metavar="FILE",
        help="desired response (.rsp/.drv/.tim RPC III, .csv, .mat, .npz) with the rig's "
        "response channels (`vrig describe RIG`) at the rig's sample rate. CSV: UTF-8, a header "
        "row 'time,<name> [<unit>],...' (first column time [s], uniformly spaced: it gives the "
        "sample rate; one column per response, matched by name, else by position), then one "
        "row of numbers per sample, comma-separated; a file without the header row is refused",
    )
    rec.add_argument(
        "--target",
        metavar="KIND",
        help="desired response to generate when no --desired file is given: 'pseudo-field' "
        "(default: the rig's response to a road-like random drive), 'field:SCENARIO' (the rig's "
        "specimen in its vehicle driven over a road: a service record, `vrig describe RIG` lists "
        "the scenarios) or 'field' (the rig's first scenario); a file path works as --desired",
    )
    rec.add_argument(
        "--iterations", type=int, default=ITERATIONS,
        help=f"iterations after IT00 (default {ITERATIONS})",
    )  # fmt: skip
    rec.add_argument(
        "--gain",
        type=float,
        help=f"iteration gain in (0, 2] (default: the rig side-car's "
        f"reconstruction.methods.METHOD.gain, else reconstruction.gain, else {DEFAULT_GAIN:g})",
    )
    add_band_argument(
        rec,
        "simulation bandwidth [Hz] (default: the rig's test band; shaker 10-60 Hz because "
        "its accelerometer is deaf below 10 Hz)",
    )
    rec.add_argument(
        "--seconds",
        type=float,
        help="length of the generated record (--target, default 30 s); with --desired, use "
        "only the first SECONDS of the file",
    )
    add_seed_argument(rec)
    rec.add_argument(
        "--format",
        dest="fmt",
        choices=("rsp", "csv", "mat", "npz"),
        default="rsp",
        help="record format of the test folder (default rsp: RPC III .drv/.rsp)",
    )
    rec.add_argument("--out", help="results folder (default ./results/<rig>-<method>)")
    rec.add_argument(
        "--overwrite", action="store_true", help="replace the records of an existing results folder"
    )


def add_model_arguments(rec) -> None:
    """Add ``reconstruct``'s inverse-model and iteration-strategy options (defaults: the rig
    side-car's ``reconstruction`` block, resolved by :func:`vrig.cli._resolve`).

    Parameters
    ----------
    rec : argparse.ArgumentParser
        The parser of ``vrig reconstruct``.
    """
    rec.add_argument(
        "--method",
        choices=METHODS,
        default="arx",
        help="inverse model: arx (QanTiM), narx, split (split spectra), frf (H1, RPC-style), "
        "error-signal (ARX + NARX of its drive error, §5.5.4); default arx. A method the "
        "reference text reports as failing on the rig runs after a one-line warning quoting "
        "it (the rig's side-car: reconstruction.methods.METHOD.unsupported, models/README.md). "
        "rattlesnake:FILE.py:NAME runs a Sandia Rattlesnake transient control law (function, "
        "generator or class NAME in FILE.py) on vrig's identification (docs/reconstruction.md)",
    )
    rec.add_argument(
        "--order",
        type=int,
        help="model order (arx/narx/split/error-signal; default: the rig side-car's "
        "reconstruction.methods.METHOD.order, else 4; error-signal: 3)",
    )
    rec.add_argument(
        "--degree",
        type=int,
        help="NARX polynomial degree (narx: default 2; split: makes the low band NARX; "
        "error-signal: of the error NARX, default 2)",
    )
    rec.add_argument(
        "--search",
        action="store_true",
        help="narx: search the inverse's structure and fitting options by free-run validation "
        "(orders up to twice --order, degrees 1..--degree, least squares / simulation focus, "
        "all / FROLS / SEMP terms; identification.NarxSearch) instead of fitting one model",
    )
    rec.add_argument(
        "--budget",
        type=float,
        metavar="S",
        help="seconds the --search may take (default 60)",
    )
    add_law_arguments(rec)
    rec.add_argument(
        "--split-hz",
        type=float,
        help="split frequency [Hz] (split; default: the rig side-car's, else the geometric mean "
        "of the band, or a quarter of its upper edge for a band from 0 Hz)",
    )
    rec.add_argument(
        "--strategy",
        choices=STRATEGIES,
        default=IterationSettings.strategy,
        help="fixed: one inverse model for the whole iteration (QanTiM; default); adaptive: "
        "re-identified from the latest drive and response before every update",
    )
    rec.add_argument(
        "--update",
        choices=UPDATES,
        default=IterationSettings.update,
        help="how the correction model learns from the iteration (vrig.reconstruction.updates): "
        "none (default: the inverse identified before IT00), frf (H1 FRF updated from every "
        "record, TWR-style), secant (per-band Broyden update), reidentify (the method refitted "
        "on identification + iteration records), ilc (norm-optimal ILC); not with --strategy "
        "adaptive",
    )
    rec.add_argument(
        "--tolerance",
        type=float,
        metavar="PCT",
        help="stop as soon as every channel's η0 [%%] is at or below PCT (default: play all "
        "--iterations)",
    )
    rec.add_argument(
        "--id-match",
        action="store_true",
        help="identify matched to the desired response (§3.3-3.4): a short probe measures the "
        "rig's FRF, the identification drive's PSD is shaped from the desired response and its "
        "level raised until the identification responses reach the desired RMS and peaks "
        "(within the drives' full scale); default: a triangular random drive at 5 %% of full "
        "scale (or the rig side-car's level), which a large, slow, non-Gaussian target outgrows",
    )


def add_law_arguments(rec) -> None:
    """The Rattlesnake control law's options of ``vrig reconstruct`` (``--law-parameters``,
    ``--law-nperseg``, ``--law-oversample``: the law's ``extra_parameters``, frame length and
    ``output_oversample_factor``; refused for other methods by the command).

    Parameters
    ----------
    rec : argparse.ArgumentParser
        The parser of ``vrig reconstruct``.
    """
    rec.add_argument(
        "--law-parameters",
        metavar="TEXT|@FILE",
        help="rattlesnake: the law's extra_parameters (Rattlesnake's free-text box), as TEXT or "
        "read from @FILE; default empty",
    )
    rec.add_argument(
        "--law-nperseg",
        type=int,
        metavar="N",
        help="rattlesnake: samples per frame of the FRF and CPSDs the law receives "
        "(frequency_spacing = fs / N; default 512)",
    )
    rec.add_argument(
        "--law-oversample",
        type=int,
        metavar="K",
        help="rattlesnake: the law's output_oversample_factor (vrig keeps every K-th sample of "
        "its drive; default 1)",
    )
