"""The PI vs fuzzy-PI comparison protocols: which gains each controller runs with, and why.

* ``matched`` (the default of ``fuzzkit compare``): the PI runs with its gains (defaults, or
  the ``pi`` entry of a gains file); the fuzzy-PI's scaling factors are derived from them by
  :func:`fuzzkit.studies.matching.matched_fuzzy_gains`, so that both have the same
  small-signal gain, measured from the rule base. Differences are then due to the surface's
  shape only.
* ``tuned``: each controller runs with the gains tuned for it (``fuzzkit tune``) on the same
  cost and scenarios; both entries must be in the gains file.
* ``default``: the hand-set defaults (``fuzzkit.studies.experiments.DEFAULT_GAINS``), with any
  gains file's entries on top. With the MacVicar-Whelan surface the default fuzzy-PI has 1.5x
  the PI's small-signal gain, so this is *not* a like-for-like comparison.
"""

from __future__ import annotations

import os
from dataclasses import dataclass

from fuzzkit.control.controllers import Surface
from fuzzkit.control.gains import read_gains, read_gains_file
from fuzzkit.control.names import GAIN_KEYS
from fuzzkit.errors import ConfigError
from fuzzkit.studies.experiments import DEFAULT_GAINS
from fuzzkit.studies.matching import matched_fuzzy_gains

PROTOCOLS = ("matched", "tuned", "default")


@dataclass(frozen=True, slots=True)
class ControllerGains:
    """The complete gains one controller runs with and a line saying where they come from."""

    controller: str
    gains: dict[str, float]
    source: str


def protocol_gains(
    protocol: str,
    surface: Surface,
    gains_path: str | os.PathLike[str] | None = None,
) -> dict[str, ControllerGains]:
    """The gains of ``pi`` and ``fuzzy-pi`` under ``protocol`` (module docstring).

    Parameters
    ----------
    protocol : ``matched``, ``tuned`` or ``default``.
    surface : the fuzzy-PI's control surface (its slopes decide the matched gains).
    gains_path : a gains file (``fuzzkit.control.gains``); required for ``tuned``.

    Raises
    ------
    ConfigError
        Unknown protocol; ``tuned`` without a gains file holding both controllers; any
        problem of the gains file.
    """
    if protocol not in PROTOCOLS:
        raise ConfigError(f"unknown protocol {protocol!r} (expected one of {', '.join(PROTOCOLS)})")
    where = f" from {gains_path}" if gains_path else ""
    out: dict[str, ControllerGains] = {}
    if protocol == "tuned":
        if gains_path is None:
            raise ConfigError(
                "--protocol tuned needs --gains FILE holding tuned gains for both pi and "
                "fuzzy-pi (fuzzkit tune E1 E2 E3 --controller pi --out FILE, then the same "
                "with --controller fuzzy-pi)"
            )
        entries = read_gains_file(gains_path)
        for ctrl in ("pi", "fuzzy-pi"):
            g = dict(DEFAULT_GAINS[ctrl])
            g.update(read_gains(gains_path, ctrl, required=True))
            entry = entries.get(ctrl)
            kept = entry is not None and entry.provenance.get("kept_defaults") is True
            note = " (the search kept the default gains)" if kept else ""
            out[ctrl] = ControllerGains(ctrl, g, f"tuned{where}{note}")
        return out
    pi = dict(DEFAULT_GAINS["pi"])
    pi_file = read_gains(gains_path, "pi")
    pi.update(pi_file)
    out["pi"] = ControllerGains("pi", pi, f"file{where}" if pi_file else "default")
    fz_file = read_gains(gains_path, "fuzzy-pi")
    if protocol == "default":
        fz = dict(DEFAULT_GAINS["fuzzy-pi"])
        fz.update(fz_file)
        out["fuzzy-pi"] = ControllerGains("fuzzy-pi", fz, f"file{where}" if fz_file else "default")
        return out
    ref = dict(DEFAULT_GAINS["fuzzy-pi"])
    ref.update(fz_file)
    m = matched_fuzzy_gains(surface, pi, ref)
    out["fuzzy-pi"] = ControllerGains("fuzzy-pi", m.gains, m.describe())
    return out


def format_gains(g: ControllerGains) -> str:
    """``pi: kp=4e-05, ki=1e-05 (default)`` for the human output of ``compare``."""
    vals = ", ".join(f"{k}={g.gains[k]:.4g}" for k in GAIN_KEYS[g.controller])
    return f"{g.controller}: {vals} ({g.source})"
