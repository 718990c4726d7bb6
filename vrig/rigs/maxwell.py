"""Rate-dependent rubber: a generalised Maxwell chain on a joint or tendon.

The element
-----------
``N`` parallel branches, each a spring ``k_i`` [N/m] in series with a linear dashpot ``c_i``
[N s/m] (relaxation time ``τ_i = c_i / k_i`` [s]), in parallel with whatever static stiffness the
joint or tendon already has (a polynomial, Iwan elements, viscous loss: kept as they are). On a
harmonic displacement ``x e^{iωt}`` the chain adds the complex stiffness ::

    K*(ω) = Σ_i k_i · iωτ_i / (1 + iωτ_i)
          = Σ_i k_i (ωτ_i)² / (1 + (ωτ_i)²)  +  i Σ_i k_i ωτ_i / (1 + (ωτ_i)²)

(storage + i loss): nothing at ``ω → 0`` (the static stiffness is the joint's own), ``Σ k_i`` at
``ω → ∞``; each branch's loss peaks at ``ω = 1/τ_i``. After a step ``x_0`` the chain's force
relaxes as ``x_0 Σ_i k_i e^{-t/τ_i}`` (a Prony series). This is the standard linear-viscoelastic
model of filled rubber in the frequency band of a mount (Gent (ed.), *Engineering with Rubber*,
Hanser, the chapter on dynamic mechanical properties: storage modulus rising with frequency and
loss factor about 0.1-0.3 for carbon-black filled natural rubber; Harris & Piersol, *Harris'
Shock and Vibration Handbook*, McGraw-Hill, the chapters on rubber isolators: dynamic-to-static
stiffness ratio about 1.2-1.6 of filled natural rubber. The ranges are the commonly quoted ones;
chapter, table and edition were not checked against the books here). The split of a filled-rubber
mount into separable elastic, friction (here the rig's Iwan elements) and viscoelastic parts is
that of García Tárrago, Kari, Viñolas & Gil-Negrete, *Polymer Testing* 26 (2007) 629-638
(carbon-black filled bushings measured 5-155 Hz; Sjöberg, *On dynamic properties of rubber
isolators*, doctoral thesis, KTH 2002, the same group's frequency- and amplitude-dependent
isolator model). Log-spaced ``τ_i`` with similar ``k_i`` give a storage stiffness that rises about
linearly in ``log f`` and a nearly constant loss, as measured on filled rubber.

Realisation: shared with the damper's series compliance
-------------------------------------------------------
A Maxwell branch is exactly a hydraulic damper with a *linear* law (``c_i``) and series stiffness
``k_i`` (:mod:`vrig.rigs.damper`): the dashpot end is the massless internal node ``x_d`` (the
activation of an actuator ``NAME_i_compliance`` with ``dyntype="user"``, part of the rig's state),
the force on the joint/tendon is ``k_i (x_d - (q - q_0))`` and the node moves at
``ẋ_d = -f / c_i``, advanced exactly per step by the damper module's compiled ``mjcb_act_dyn``
hook. :meth:`MaxwellChain.branches` therefore returns one :class:`~vrig.rigs.damper.Damper` per
branch (``damping = k_i τ_i``, ``series_stiffness = k_i``); :func:`realise` writes their
compliance actuators (leaving the joint's own damping alone), and the rig binds and installs them
with its dampers (:func:`vrig.rigs.damper.bind`, :func:`~vrig.rigs.damper.install`). A branch
with ``k_i = 0`` is absent from the model: a chain of zeros leaves the model as hand-written, bit
for bit.

A rig declares its chains in the side-car (``"maxwell"``, ``models/README.md``); parameters set a
branch's stiffness or relaxation time by ``{"maxwell": NAME, "field": F, "index": i}`` rules.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from ._checks import check_number
from .damper import Damper, add_compliance

__all__ = ["MaxwellChain", "realise"]


@dataclass(frozen=True)
class MaxwellChain:
    """A generalised Maxwell chain (SI units; see the module for the law).

    Attributes
    ----------
    name : str
        The chain's name; branch ``i`` (from 1) is realised as the actuator
        ``NAME_i_compliance``.
    relaxation_time : tuple of float
        ``τ_i`` [s] (> 0) of every branch.
    stiffness : tuple of float or None
        ``k_i`` [N/m] (>= 0) of every branch, as many as ``relaxation_time``; None: all 0 (the
        chain declared, no branch realised).
    joint : str or None
        The MJCF slide joint the chain acts on (exactly one of joint, tendon).
    tendon : str or None
        The MJCF tendon the chain acts on.
    """

    name: str
    relaxation_time: tuple
    stiffness: tuple | None = None
    joint: str | None = None
    tendon: str | None = None

    FIELDS = ("stiffness", "relaxation_time")
    """The per-branch fields a side-car parameter may set (``{"maxwell": NAME, "field": F,
    "index": i}``)."""

    def __post_init__(self):
        """Validate and normalise the chain (a :class:`~vrig.errors.RigParameterError` names
        the field)."""
        taus = tuple(float(check_number(f"maxwell {self.name!r}: relaxation_time", t,
                                        exclusive_minimum=0)) for t in self.relaxation_time)  # fmt: skip
        if not taus:
            raise ValueError(f"maxwell {self.name!r}: give at least one relaxation_time")
        ks = (0.0,) * len(taus) if self.stiffness is None else self.stiffness
        ks = tuple(float(check_number(f"maxwell {self.name!r}: stiffness", k, minimum=0))
                   for k in ks)  # fmt: skip
        if len(ks) != len(taus):
            raise ValueError(
                f"maxwell {self.name!r}: {len(ks)} stiffness values for {len(taus)} "
                "relaxation times (one per branch)"
            )
        if (self.joint is None) == (self.tendon is None):
            raise ValueError(
                f"maxwell {self.name!r}: give exactly one of joint and tendon, got "
                f"joint={self.joint!r}, tendon={self.tendon!r}"
            )
        object.__setattr__(self, "relaxation_time", taus)
        object.__setattr__(self, "stiffness", ks)

    def with_branch(self, field: str, index: int, value: float) -> MaxwellChain:
        """A copy with branch ``index`` (from 0) of ``field`` set to ``value`` (checked).

        Parameters
        ----------
        field : str
            ``"stiffness"`` [N/m] or ``"relaxation_time"`` [s].
        index : int
            The branch, 0 .. N-1.
        value : float
            The new value in the field's SI unit.
        """
        if field not in self.FIELDS:
            raise ValueError(
                f"maxwell {self.name!r}: unknown field {field!r}; known: {list(self.FIELDS)}"
            )
        values = list(getattr(self, field))
        if not 0 <= index < len(values):
            raise IndexError(
                f"maxwell {self.name!r}: branch index {index} outside 0..{len(values) - 1}"
            )
        values[index] = value
        return MaxwellChain(**{**self._as_dict(), field: tuple(values)})

    def _as_dict(self) -> dict:
        """The fields as keywords."""
        return dict(name=self.name, relaxation_time=self.relaxation_time,
                    stiffness=self.stiffness, joint=self.joint, tendon=self.tendon)  # fmt: skip

    def branches(self) -> tuple:
        """The realised branches as linear :class:`~vrig.rigs.damper.Damper` elements with
        series compliance (``damping = k_i τ_i`` [N s/m], ``series_stiffness = k_i``), named
        ``NAME_i`` (i from 1); branches with ``k_i = 0`` are left out."""
        pairs = zip(self.stiffness, self.relaxation_time, strict=True)
        return tuple(
            Damper(
                f"{self.name}_{i + 1}",
                joint=self.joint,
                tendon=self.tendon,
                damping=k * tau,
                series_stiffness=k,
            )
            for i, (k, tau) in enumerate(pairs)
            if k > 0
        )

    def complex_stiffness(self, frequency_hz) -> np.ndarray:
        """The chain's complex stiffness ``K*(ω) = Σ k_i iωτ_i / (1 + iωτ_i)`` [N/m]: real part
        storage, imaginary part loss.

        Parameters
        ----------
        frequency_hz : float or array_like
            Frequencies in Hz.
        """
        f = np.asarray(frequency_hz, dtype=float)
        iwt = 1j * 2 * np.pi * f[..., None] * np.asarray(self.relaxation_time)
        return np.sum(np.asarray(self.stiffness) * iwt / (1.0 + iwt), axis=-1)

    def relaxation(self, t) -> np.ndarray:
        """The chain's relaxation stiffness ``Σ k_i exp(-t/τ_i)`` [N/m] at times ``t`` [s] after
        a unit step of displacement (the force per metre of the step).

        Parameters
        ----------
        t : float or array_like
            Times since the step in s (>= 0).
        """
        t = np.asarray(t, dtype=float)
        tau = np.asarray(self.relaxation_time)
        return np.sum(np.asarray(self.stiffness) * np.exp(-t[..., None] / tau), axis=-1)


def realise(spec: mujoco.MjSpec, chain: MaxwellChain) -> None:
    """Write ``chain``'s branches into ``spec`` as the damper module's compliance actuators
    (:func:`vrig.rigs.damper.add_compliance`); the joint's or tendon's own stiffness and damping
    are left as they are. Nothing is written for a chain whose stiffnesses are all 0.

    Parameters
    ----------
    spec : mujoco.MjSpec
        The rig's model specification (edited in place).
    chain : MaxwellChain
        The element.

    Raises
    ------
    ValueError
        If the joint or tendon is not in ``spec``, or an actuator name is already taken.
    """
    kind, target = ("joint", chain.joint) if chain.joint is not None else ("tendon", chain.tendon)
    branches = chain.branches()
    if branches and getattr(spec, kind)(target) is None:
        raise ValueError(f"maxwell {chain.name!r}: no {kind} {target!r} in the model")
    for branch in branches:
        add_compliance(spec, branch, kind, target)
