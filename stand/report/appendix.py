"""The certificate's page 2: the measurement behind it (the supports, the parameter
tolerances, the spectrum and speed, the warnings) and the few parameters a customer
needs; formatting only, in the language it is given."""

from __future__ import annotations

import html
from pathlib import PurePath
from typing import Any

from stand.i18n.display import Display
from stand.i18n.language import ENGLISH, Language
from stand.report.plots import spectrum_and_speed
from stand.solve import Result


def file_name(path: str | None) -> str:
    """A file as a customer's paper names it: its name, never the stand's folders."""
    return PurePath(path).name if path else "–"


def _uncertainty(out: dict[str, Any], _: Language) -> str:
    pu = out.get("parameter_uncertainty")
    if pu is None:
        return ""
    t = pu["tolerances"]
    d = Display.of(out, _)
    rows = "".join(
        f"<tr><td>{p['plane']}</td><td>±{d.number(p['radius95_monte_carlo_g_mm'])}</td>"
        f"<td>±{d.number(p['radius95_linear_g_mm'])}</td>"
        f"<td>±{d.number(p['combined_g_mm'])}</td>"
        f"<td class=l>{', '.join(f'{k} {100 * s:.0f} %' for k, s in p['largest_shares'])}</td></tr>"
        for p in pu["planes"]
    )
    e = html.escape
    return (
        f"<h2>{e(_('Parameter tolerances'))}</h2><p class=muted>" + e(_(
            "Uniform within C ±{c} %, M and J3 ±{m} %, lengths ±{length}, sensor gains "
            "±{gain} %; {draws} Monte Carlo draws.").format(
            c=f"{t['C_pct']:g}", m=f"{t['M_pct']:g}", length=d.length(t["length_mm"]),
            gain=f"{t['gain_pct']:g}", draws=pu["draws"])) + "</p>"
        f"<table><tr><th>{e(_('plane'))}</th>"
        f"<th>{e(_('95 % [{unit}], Monte Carlo').format(unit=d.unbalance_unit))}</th>"
        f"<th>{e(_('linearised'))}</th><th>{e(_('with the measurement'))}</th>"
        f"<th class=l>{e(_('largest shares'))}</th></tr>{rows}</table>"
    )  # fmt: skip


def appendix(out: dict[str, Any], result: Result, _: Language) -> str:
    e = html.escape
    supports = "".join(
        f"<tr><td>{s['node']}</td><td>{s['amplitude_m_s2']:.4f} ± {s['uncertainty_m_s2']:.4f}</td>"
        f"<td>{s['phase_deg']:.2f}°</td><td>{s['revolutions']:.0f}</td>"
        f"<td>{s['noise_m_s2']:.4f}</td></tr>"
        for s in out["supports"]
    )
    warnings = (
        "".join(f'<div class="warn">{e(_(w))}</div>' for w in out["warnings"])
        or f"<p class=muted>{e(_('no warnings'))}</p>"
    )
    spectrum, speed = spectrum_and_speed(result.traces, out["rpm"], _)
    p = result.provenance
    meta = {
        _("run file"): file_name(p.run_file), _("start time (UTC)"): p.start_time,
        _("frames"): p.frames, _("duration [s]"): round(p.duration_s, 3),
        **_parameters(out, _),
    }  # fmt: skip
    rows = "".join(
        f"<tr><th class=l>{e(str(k))}</th><td class=l>{e(str(v))}</td></tr>"
        for k, v in meta.items()
    )
    heads = "".join(f"<th>{e(h)}</th>" for h in (
        _("support"), _("1x amplitude [m/s²] (95 %)"), _("phase"), _("revolutions"),
        _("noise at 1x [m/s²]")))  # fmt: skip
    kept = _(
        "The whole configuration is kept in the stand's archive under its SHA-256 ({digest}…)."
    ).format(digest=p.config_sha256[:16])
    return f"""<div class=appendix>
<h2>{e(_("Measurement"))}</h2>
<table><tr>{heads}</tr>{supports}</table>
{_uncertainty(out, _)}
<h2>{e(_("Spectrum around 1x"))}</h2><img alt="spectrum" src="{spectrum}">
<h2>{e(_("Speed over the run"))}</h2><img class=speed alt="speed" src="{speed}">
<h2>{e(_("Warnings"))}</h2>{warnings}
<div class=keep><h2>{e(_("Run and parameters"))}</h2><table>{rows}</table>
<p class=muted>{e(kept)}</p></div>
</div>"""


def _parameters(out: dict[str, Any], _: Language = ENGLISH) -> dict[str, str]:
    """The few parameters a customer needs (the rest stays in the archive)."""
    d = Display.of(out, _)
    got = {_("speed [rpm]"): f"{out['rpm']:.0f}"}
    for x in out.get("planes", []):
        if x.get("radius_mm") is not None:
            got[_("plane {i}: correction radius").format(i=x["plane"])] = d.length(x["radius_mm"])
    t = out.get("tolerance") or {}
    if t.get("source"):
        got[_("tolerance")] = str(t["source"])
    return got
