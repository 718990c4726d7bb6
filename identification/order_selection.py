"""Model-order selection: modelling error versus order for each output channel (Fig. 3.21)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import metrics
from ._validation import as_signal, check_same_length
from .errors import IdentificationError, InsufficientDataError, SimulationDivergedError
from .models import Narx

__all__ = ["OrderScan", "order_scan"]


@dataclass(frozen=True)
class OrderScan:
    """Result of :func:`order_scan`.

    Attributes
    ----------
    orders : ndarray (n_orders,)
        The model orders tried.
    errors : ndarray (n_orders, ny)
        Free-run η0 [%] (eq. 5-28) per order and output channel, the free run started from the
        record's own first ``order`` outputs and scored after them; ``inf`` where the model's free
        run diverged (see ``diverged``) or the record was too short for that order.
    diverged : ndarray of bool (n_orders, ny)
        True where that order's free run left its bound on that channel.
    n_terms : ndarray (n_orders,)
        Terms per channel at each order.
    best : ndarray (ny,)
        Order with the smallest error per channel.
    """

    orders: np.ndarray
    errors: np.ndarray
    diverged: np.ndarray
    n_terms: np.ndarray
    best: np.ndarray

    def table(self, output_names=None) -> str:
        """Plain-text table: one row per order, one column per channel.

        Parameters
        ----------
        output_names : sequence of str, optional
            Column headings, one per output channel (default ``y1, y2, ...``).
        """
        ny = self.errors.shape[1]
        names = output_names or [f"y{k + 1}" for k in range(ny)]
        head = f"{'order':>5} {'terms':>6} " + " ".join(f"{n:>10}" for n in names)
        rows = [head]
        for i, n in enumerate(self.orders):
            cells = " ".join(
                f"{'diverged':>10}" if self.diverged[i, k] else f"{self.errors[i, k]:>9.2f}%"
                for k in range(ny)
            )
            rows.append(f"{n:>5} {self.n_terms[i]:>6} {cells}")
        return "\n".join(rows)


def order_scan(u, y, orders, *, degree: int = 1, validation=None, solver="qr", kind="full"):
    """Identify a model for each order and report the free-run η0 per output channel.

    Parameters
    ----------
    u, y : arrays (N, nu), (N, ny)
        Identification data.
    orders : iterable of int
        Orders to try.
    degree : int
        Polynomial degree (1 = ARX).
    validation : tuple (u_val, y_val), optional
        Records the error is measured on (default: the identification data).
    solver : str or callable
        Least-squares solver (see :func:`~identification.solvers.get_solver`).
    kind : {"full", "pure", "quasi-static", "input-polynomial"}
        Term set of the models (see :class:`~identification.Narx`).
    """
    u = as_signal(u, "u")
    y = as_signal(y, "y")
    check_same_length(u, y, "u", "y")
    orders = np.array(sorted(set(int(n) for n in orders)))
    if orders.size == 0 or orders.min() < 0:
        raise IdentificationError("orders must be a non-empty list of non-negative integers")
    if validation is None:
        uv, yv = u, y
    else:
        uv = as_signal(validation[0], "validation u", n_channels=u.shape[1])
        yv = as_signal(validation[1], "validation y", n_channels=y.shape[1])
        check_same_length(uv, yv, "validation u", "validation y")
    ny = y.shape[1]
    errors = np.full((orders.size, ny), np.inf)
    diverged = np.zeros((orders.size, ny), dtype=bool)
    n_terms = np.zeros(orders.size, dtype=np.int64)
    for i, n in enumerate(orders):
        model = Narx(int(n), degree, solver=solver, kind=kind)
        try:
            model.fit(u, y)
        except InsufficientDataError:
            continue
        n_terms[i] = model.n_terms_[0]
        p = model.max_lag_
        y0 = yv[:p]  # the record's own initial outputs: no start-up transient
        try:
            errors[i] = metrics.qantim_fit_dc(yv[p:], model.simulate(uv, y0=y0)[p:])
        except SimulationDivergedError as exc:
            diverged[i, :] = True
            # the other channels are still scored without the diverging one's feedback bound
            try:
                sim = model.simulate(uv, y0=y0, bound=np.inf)
                errors[i] = metrics.qantim_fit_dc(yv[p:], sim[p:])
                diverged[i, :] = False
                diverged[i, exc.channel] = True
                errors[i, exc.channel] = np.inf
            except SimulationDivergedError:
                pass
    best = orders[np.argmin(errors, axis=0)]
    return OrderScan(orders=orders, errors=errors, diverged=diverged, n_terms=n_terms, best=best)
