"""The page of a re-judgement (``stand reprocess --report``): the recall list, the runs whose
verdict changed, the runs that could not be re-solved, and each plane's new residual
against the archived one with the tolerance.  Formatting only: the page comes from the one
JSON object :func:`stand.reprocess.rejudge.summary` gives."""

from __future__ import annotations

import html
from typing import Any

from stand.report.certificate import CSS
from stand.report.plots import png


def _scatter(out: dict[str, Any]) -> str:
    """Per plane, how far each run's unbalance moved (re-judged minus archived) against the
    archived value [g mm], the tolerance dotted; red: a run that passed and fails now."""
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(10, 4.2))
    ok = [r for r in out["runs"] if "after" in r]
    for i, ax in enumerate(axes):
        pts, per = [], None
        for r in ok:
            b, a = r["before"]["planes"][i], r["after"]["planes"][i]
            worse = b["pass"] is not False and a["pass"] is False
            pts.append((b["unbalance_g_mm"], a["unbalance_g_mm"] - b["unbalance_g_mm"], worse))
            per = a.get("permissible_g_mm") or per
        for flag, colour, size, label in (
            (False, "0.35", 8, "runs"),
            (True, "tab:red", 22, "passed, fails now"),
        ):
            x = [p[0] for p in pts if p[2] is flag]
            y = [p[1] for p in pts if p[2] is flag]
            if x:
                ax.scatter(x, y, s=size, color=colour, label=label, zorder=3)  # fmt: skip
        ax.axhline(0.0, color="0.6", lw=1)
        if per:
            ax.axvline(per, color="tab:green", ls="--", lw=1.2, label=f"tolerance {per:.0f} g mm")
        ax.set_xlabel(f"plane {i + 1}: archived unbalance [g mm]")
        ax.set_ylabel("re-judged minus archived [g mm]")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8, loc="best")
    fig.tight_layout()
    return png(fig)


def _planes(r: dict[str, Any], side: str) -> str:
    return "<br>".join(
        f"{p['unbalance_g_mm']:.1f} ± {p['uncertainty_g_mm']:.1f} at {p['angle_deg']:.1f}°"
        for p in r[side]["planes"]
    )


def render_reprocess(out: dict[str, Any]) -> str:
    """A re-judgement as one self-contained HTML page."""
    e = html.escape
    c = out["counts"]
    changed = [r for r in out["runs"] if "after" in r
               and r["after"]["verdict"] != r["before"]["verdict"]]  # fmt: skip
    rows = "".join(
        f"<tr><td>{r['run_id']}</td><td class=l>{e(r['serial'] or '–')}</td>"
        f"<td class=l>{r['kind']}</td><td>{_planes(r, 'before')}</td><td>{_planes(r, 'after')}</td>"
        f"<td class=l>{r['before']['verdict']} → <b>{r['after']['verdict']}</b></td></tr>"
        for r in changed
    )
    faults = "".join(
        f"<tr><td>{r['run_id']}</td><td class=l>{e(r['serial'] or '–')}</td>"
        f"<td class=l>{r['status']}</td><td class=l>{e(str(r.get('reason') or ''))}</td></tr>"
        for r in out["runs"] if r["status"] not in ("ok",)
    )  # fmt: skip
    recall = ", ".join(e(s) for s in out["recall"]) or "none"
    statuses = ", ".join(f"{k} {c[k]}" for k in ("ok", "missing", "altered", "unreadable",
                                                  "refused", "pending") if k in c)  # fmt: skip
    return f"""<!doctype html>
<html lang="en"><head><meta charset="utf-8"><title>Revision {e(out["revision"])}</title>
<style>{CSS}</style></head><body>
<header><h1>Re-judged: revision {e(out["revision"])}</h1></header>
<p>{c["runs"]} archived runs re-solved from their files ({statuses}). The verdict changed
in {c["verdicts_changed"]} runs; of {c["serials"]} rotors, <b>{c["recall"]}</b> passed and
are out of tolerance now, {c["cleared"]} failed and are within it now.</p>
<h2>Recall list</h2><p class=big>{recall}</p>
<h2>Runs whose verdict changed</h2>
<table><tr><th>run</th><th class=l>serial</th><th class=l>kind</th>
<th>archived [g mm]</th><th>re-judged [g mm]</th><th class=l>verdict</th></tr>{rows}</table>
<p class=muted>Per plane, 1 then 2: unbalance ± its 95 % interval at the angle from the
reference mark, against the direction of rotation.</p>
<h2>Runs not re-solved</h2>
<table><tr><th>run</th><th class=l>serial</th><th class=l>status</th><th class=l>why</th></tr>
{faults or "<tr><td colspan=4 class=l>none</td></tr>"}</table>
<h2>How far each answer moved</h2>
<img alt="re-judged minus archived unbalance, per plane" src="{_scatter(out)}">
<p class=muted>A run right of the tolerance line failed as archived; a red one passed and
fails now.</p>
</body></html>
"""
