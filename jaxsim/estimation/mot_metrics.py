"""CLEAR MOT metrics of a multi-object tracker (Bernardin & Stiefelhagen 2008), on the host (NumPy/SciPy).

Per frame, ground-truth objects and the tracker's hypotheses (ids and positions) are matched:

1. an object's most recent correspondence (object ↔ hypothesis, from any earlier frame) is kept if
   both are present and their distance is within ``threshold`` (objects in the frame's order);
2. the remaining objects and hypotheses are matched by a minimum-cost assignment (Hungarian) on the
   squared distance, pairs beyond ``threshold`` excluded;
3. an object matched to a hypothesis other than the one it was last matched to (in any earlier frame)
   is an identity switch.

Unmatched objects are misses (FN), unmatched hypotheses false positives (FP);
``MOTA = 1 − (FN + FP + IDSW) / number of object instances`` and MOTP is the mean distance of the
matches.  These are the rules of the ``motmetrics`` package (``MOTAccumulator`` with squared Euclidean
distances), which the tests use as the oracle.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np
from scipy.optimize import linear_sum_assignment


@dataclass(frozen=True)
class MOTResult:
    """Counts over all frames and the match distances (m or the positions' unit)."""

    num_objects: int
    misses: int
    false_positives: int
    switches: int
    distances: np.ndarray

    @property
    def mota(self) -> float:
        """``1 − (FN + FP + IDSW) / objects`` (a fraction; × 100 for %)."""
        return 1.0 - (self.misses + self.false_positives + self.switches) / max(self.num_objects, 1)

    @property
    def motp(self) -> float:
        """Mean distance of the matched pairs."""
        return float(np.mean(self.distances)) if self.distances.size else float("nan")


def clear_mot(
    object_ids: Sequence[np.ndarray],
    object_pos: Sequence[np.ndarray],
    hyp_ids: Sequence[np.ndarray],
    hyp_pos: Sequence[np.ndarray],
    threshold: float,
) -> MOTResult:
    """CLEAR MOT over frames: per frame ``object_ids (n_o,)``, ``object_pos (n_o, d)``, ``hyp_ids (n_h,)``,
    ``hyp_pos (n_h, d)``; a pair matches only if its Euclidean distance is below ``threshold``."""
    if not (len(object_ids) == len(object_pos) == len(hyp_ids) == len(hyp_pos)):
        raise ValueError("object_ids, object_pos, hyp_ids, hyp_pos: need one entry per frame each")
    if not (np.isfinite(threshold) and threshold > 0):
        raise ValueError(f"threshold: expected a positive distance, got {threshold!r}")
    last: dict[int, int] = {}  # object → the hypothesis it was matched to most recently
    n_obj = misses = fps = switches = 0
    dists: list[float] = []
    for oid, opos, hid, hpos in zip(object_ids, object_pos, hyp_ids, hyp_pos):
        oid, hid = [int(i) for i in np.asarray(oid)], [int(i) for i in np.asarray(hid)]
        opos, hpos = np.asarray(opos, float).reshape(len(oid), -1), np.asarray(hpos, float).reshape(len(hid), -1)
        d2 = np.sum((opos[:, None, :] - hpos[None, :, :]) ** 2, axis=-1)
        ok = d2 <= threshold**2
        pairs: dict[int, int] = {}  # object row → hypothesis column
        for r, o in enumerate(oid):  # 1. the object's last correspondence, if still present and close
            h = last.get(o)
            if h is not None and h in hid and hid.index(h) not in pairs.values() and ok[r, hid.index(h)]:
                pairs[r] = hid.index(h)
        rows = [r for r in range(len(oid)) if r not in pairs]
        cols = [c for c in range(len(hid)) if c not in pairs.values()]
        if rows and cols:
            cost = np.where(ok[np.ix_(rows, cols)], d2[np.ix_(rows, cols)], np.inf)
            finite = np.isfinite(cost)
            big = (cost[finite].max() + 1.0) * (len(rows) + len(cols)) if finite.any() else 1.0
            rr, cc = linear_sum_assignment(np.where(finite, cost, big))
            for a, b in zip(rr, cc):
                if finite[a, b]:
                    pairs[rows[a]] = cols[b]
        for r, c in pairs.items():
            o, h = oid[r], hid[c]
            if o in last and last[o] != h:
                switches += 1
            last[o] = h
            dists.append(float(np.sqrt(d2[r, c])))
        n_obj += len(oid)
        misses += len(oid) - len(pairs)
        fps += len(hid) - len(pairs)
    return MOTResult(n_obj, misses, fps, switches, np.asarray(dists))


__all__ = ["MOTResult", "clear_mot"]
