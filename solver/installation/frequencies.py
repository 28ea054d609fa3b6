"""The excitation frequencies of the vibration stages, chosen from the ranked modes of the
settled joint (:func:`choose_frequencies`), or resolved for an explicit ``[[schedule]]``
(:func:`schedule_excitations`), each with the reason for it."""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from solver.dynamics.loads import Schedule
from solver.installation.settings import VibrationSettings
from solver.modal.ranking import ModeRecord


@dataclass(frozen=True)
class Excitation:
    """One vibration stage of the automatic schedule and why it was chosen."""

    frequency_Hz: float
    amplitude_N: float | str
    role: str  #: lead-in | modal | control
    mode: int  #: mode number (0: none)
    m: int
    n: int
    rank: int
    reason: str
    #: the frequency the force is applied at [Hz]: for a stage at a natural frequency the
    #: time-discrete model's natural frequency of that mode (``planning.compensate``); None: frequency_Hz
    forcing_Hz: float | None = None

    @property
    def drive_Hz(self) -> float:
        """The frequency of the force [Hz]."""
        return self.frequency_Hz if self.forcing_Hz is None else self.forcing_Hz


PAIR_TOLERANCE = 0.02  #: relative frequency difference within which two modes are one pair
MIN_FREQUENCY_HZ = 1.0  #: modes below this are not excited [Hz]


def _modal(record: ModeRecord, settings: VibrationSettings, reason: str) -> Excitation:
    """The excitation of a chosen mode at the modal stages' amplitude."""
    return Excitation(
        record.frequency_Hz,
        settings.amplitude_N,
        "modal",
        record.mode,
        record.m,
        record.n,
        record.rank,
        reason,
    )


def choose_frequencies(records: list[ModeRecord], settings: VibrationSettings) -> list[Excitation]:
    """Excitation stages from the ranking of the settled joint's modes.

    * the lead-in frequencies (docs/physics.md §3 reference sequence) at the eccentric amplitude;
    * the ``n_frequencies`` best-ranked distinct frequencies up to ``max_frequency_hz``
      (one per degenerate pair: modes within ``PAIR_TOLERANCE`` of a chosen frequency are
      its partner);
    * the lowest (m = 2, n = 1) mode among all computed modes if not among them (docs/physics.md §5.4: the
      most effective; also above ``max_frequency_hz``, unless ``m2n1_mode`` is false);
    * a non-modal control frequency: the point of [f_lo / 2, f_hi] farthest from every computed
      natural frequency and every lead-in frequency in ratio (|ln(f / f_n)|: the dynamic
      amplification of a mode depends on f / f_n; at a lead-in frequency the joint has already
      settled to what that excitation holds), f_lo and f_hi the lowest and highest chosen natural
      frequency (with a single
      chosen frequency f: f_hi = min(1.5 f, max_frequency_hz)). The octave below f_lo admits a
      control in the quasi-static band below the lowest modes, where a point between dense
      higher modes may lie within a few per cent of one (docs/install.md).
    Stages are returned in increasing frequency after the lead-in.
    """
    # below MIN_FREQUENCY_HZ: rigid-body motions of a part the contact does not hold, not modes
    modes = [r for r in records if r.frequency_Hz >= MIN_FREQUENCY_HZ]
    candidates = [r for r in modes if r.frequency_Hz <= settings.max_frequency_hz]
    chosen: list[Excitation] = []

    def same_pair(r: ModeRecord) -> bool:  # the partner of a degenerate pair (or a near-tie)
        return any(
            abs(r.frequency_Hz - c.frequency_Hz) <= PAIR_TOLERANCE * c.frequency_Hz for c in chosen
        )

    for r in sorted(candidates, key=lambda r: (r.rank, r.mode)):
        if len(chosen) >= settings.n_frequencies:
            break
        if same_pair(r):
            continue
        chosen.append(
            _modal(
                r,
                settings,
                f"rank {r.rank} of {len({x.rank for x in records})}: resonant "
                f"interface slip {max(r.resonant_slip_axial_um, r.resonant_slip_lateral_um):.3g} um",
            )
        )
    m2n1 = [r for r in modes if (r.m, r.n) == (2, 1)]
    if settings.m2n1_mode and m2n1 and all((c.m, c.n) != (2, 1) for c in chosen):
        r = min(m2n1, key=lambda r: r.frequency_Hz)
        if not same_pair(r):
            above = (
                f", above the ranked choice's {settings.max_frequency_hz:g} Hz"
                if r.frequency_Hz > settings.max_frequency_hz
                else ""
            )
            chosen.append(
                _modal(
                    r,
                    settings,
                    f"lowest m = 2, n = 1 mode (docs/physics.md §5.4: most effective in the "
                    f"experiments{above})",
                )
            )
    chosen.sort(key=lambda e: e.frequency_Hz)
    if settings.control and chosen:
        natural = np.array([r.frequency_Hz for r in modes])
        avoided = np.concatenate([natural, settings.lead_in_hz])
        lo, hi = chosen[0].frequency_Hz, chosen[-1].frequency_Hz
        if hi - lo < 1e-6 * hi:
            hi = min(1.5 * hi, settings.max_frequency_hz)
        grid = np.geomspace(0.5 * lo, hi, 2001)
        ratio = np.min(np.abs(np.log(grid[:, None] / avoided[None, :])), axis=1)
        f_c = float(grid[np.argmax(ratio)])
        nearest = float(natural[np.argmin(np.abs(np.log(f_c / natural)))])
        chosen.append(
            Excitation(
                f_c,
                settings.amplitude_N,
                "control",
                0,
                -1,
                -1,
                0,
                f"non-modal control: a factor {np.exp(np.abs(np.log(f_c / nearest))):.2f} from the "
                f"nearest natural frequency ({nearest:.1f} Hz)",
            )
        )
        chosen.sort(key=lambda e: e.frequency_Hz)
    lead = [
        Excitation(
            f,
            "eccentric",
            "lead-in",
            0,
            -1,
            -1,
            0,
            "docs/physics.md §3 reference sequence, eccentric amplitude",
        )
        for f in settings.lead_in_hz
    ]
    return lead + chosen


def schedule_excitations(
    schedule: Schedule, natural_hz: list[float], chosen: list[Excitation]
) -> list[Excitation]:
    """One Excitation per stage of an explicit schedule: 'mode k' at the k-th natural frequency,
    'ranked k' at the k-th best-ranked chosen natural frequency (with its reason)."""
    ranked = sorted((e for e in chosen if e.role == "modal"), key=lambda e: (e.rank, e.mode))
    resolved = schedule.with_natural_frequencies(natural_hz, [e.frequency_Hz for e in ranked])
    out = []
    for s, r in zip(schedule.stages, resolved.stages):
        f = float(r.frequency_hz)
        if s.ranked_number is not None:
            e = ranked[s.ranked_number - 1]
            out.append(
                replace(
                    e,
                    amplitude_N=s.amplitude_N,
                    role="schedule",
                    reason=f"[[schedule]] ranked {s.ranked_number}: {e.reason}",
                )
            )
        elif s.mode_number is not None:
            out.append(
                Excitation(
                    f, s.amplitude_N, "schedule", s.mode_number, -1, -1, 0, "[[schedule]] mode"
                )
            )
        else:
            what = "no vibration" if f == 0 or s.amplitude_N == 0 else "[[schedule]] of the case"
            out.append(Excitation(f, s.amplitude_N, "schedule", 0, -1, -1, 0, what))
    return out
