"""The station's screens (NiceGUI): Start, Measure, Correct, Check, History.

Each screen formats what :class:`stand.station.service.Station` holds; none
measures.  One page frame (the header with the five screens) hosts the
screens as NiceGUI sub pages; the live screens redraw from the station's
snapshot four times a second.  Large type and large buttons: the station is
read from two metres and worked with a keyboard or a finger.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from nicegui import app, ui

from stand.i18n import Display
from stand.i18n.language import N_, Language
from stand.plant import TokenGate
from stand.solve import to_json
from stand.station.certificates import certificate_links
from stand.station.drive_views import drive_line, index_line, turn_buttons
from stand.station.face import SEEN_FROM, face_svg
from stand.station.guard import session_of
from stand.station.history import REFRESH_S, guard, history_screen, notify
from stand.station.login import (
    add_login_routes,
    login_screen,
    require,
    who_line,
    words,
)
from stand.station.routes import add_routes
from stand.station.service import Station
from stand.station.setup import setup_screen
from stand.station.start import start_screen
from stand.station.views import (
    ANGLE_NOTE,
    check_rows,
    check_verdict,
    instructions,
    live_numbers,
    plane_status,
    planes_live,
    polar_chart,
)
from stand.station.web import harden, served_hosts

SCREENS = (("/", N_("Start")), ("/measure", N_("Measure")), ("/correct", N_("Correct")),
           ("/check", N_("Check")), ("/history", N_("History")),
           ("/setup", N_("Setup")))  # fmt: skip
RUN_KINDS = {"initial": N_("initial"), "check": N_("check")}
"""A run's kind, as the screens name it."""
STYLE = """
<style>
  body { font-size: 20px; }
  .big { font-size: 2.2rem; font-weight: 700; line-height: 1.25; }
  .huge { font-size: 3rem; font-weight: 800; }
  .pass { color: #1b5e20; } .fail { color: #b71c1c; }
  .q-field__native, .q-field__label, .q-item__label { font-size: 1.25rem !important; }
  .q-btn { font-size: 1.2rem; }
  .q-table th, .q-table td { font-size: 1.2rem !important; }
  .q-table a { color: #1565c0; text-decoration: underline; }
  .below-header { margin-top: 136px !important; }
  .instruction { font-size: 1.7rem; font-weight: 800; line-height: 1.2; }
  .actions .q-btn .block { white-space: normal; }
  .actions { position: sticky; bottom: 0; background: #fff; z-index: 5; width: 100%; }
  .station-header .nav { font-size: 1.05rem; padding: 4px 12px; }
  .station-header .logout { font-size: 0.9rem !important; padding: 2px 10px !important; }
  @media (max-width: 1279px) { .station-title { display: none; } }
</style>
"""


def _units(station: Station, _: Language) -> Display:
    s = station.snapshot()
    out = _out(s.result)
    return Display.of(out or {}, _)


def _out(result: Any) -> dict[str, Any] | None:
    return None if result is None else to_json(result)


def frame(station: Station) -> None:
    """The page frame: the header with the screens, then the screen the address names (or
    the log-in, where the stand has accounts and this browser no session)."""
    ui.add_head_html(STYLE)
    request = ui.context.client.request
    session = session_of(station, request)
    app.storage.client["lang"] = None if session is None else session.language
    _ = words(station)
    if station.sessions.required() and session is None:
        with ui.header().classes("items-center bg-blue-grey-9 q-px-md"):
            ui.label(_("Balancing station")).classes("text-h5 q-mr-lg")
        with ui.column().classes("w-full q-pa-md"):
            login_screen(_, failed=request.query_params.get("login"))
        return
    app.storage.client["session"] = None if session is None else session.token
    with ui.header().classes("column bg-blue-grey-9 q-px-md q-py-xs station-header"):
        with ui.row().classes("w-full items-center no-wrap"):  # the screens, one row
            ui.label(_("Balancing station")).classes("text-h6 q-mr-md station-title")
            for path, name in SCREENS:
                ui.button(_(name), on_click=lambda p=path: ui.navigate.to(p)).props(
                    "flat dense color=white"
                ).classes("nav").mark(f"nav-{name.lower()}")
        with ui.row().classes("w-full items-center no-wrap"):  # what it does, and who
            status = ui.label().classes("text-subtitle1 ellipsis").mark("status")
            ui.space()
            who_line(station, session, _)

        def show_status() -> None:
            s = station.snapshot()
            who, kind = s.job.serial or "-", _(RUN_KINDS.get(s.kind or "", s.kind or ""))
            status.text = {
                "idle": _("ready"),
                "measuring": _("measuring {who} ({kind} run)"),
                "done": _("{who}: {kind} run done"),
                "failed": _("{who}: {kind} run failed"),
            }[s.phase].format(who=who, kind=kind)

        ui.timer(REFRESH_S, show_status)
    ui.sub_pages({
        "/": lambda: start_screen(station),
        "/measure": lambda: measure_screen(station),
        "/correct": lambda: correct_screen(station),
        "/check": lambda: check_screen(station),
        "/history": lambda: history_screen(station),
        "/setup": lambda: setup_screen(station),
    }).classes("w-full q-pa-md")  # fmt: skip


def _waiting(s: Any, head: str, sub: str, _: Language) -> tuple[str, str]:
    """The Measure screen's two lines before the first estimate."""
    if s.phase == "idle":
        return _("Nothing measured yet"), _("start a rotor on the Start screen")
    if s.phase == "failed":
        return _("The run failed"), s.error
    if s.phase == "measuring":
        who = _("{kind} run of {rotor}: starting").format(
            kind=_(RUN_KINDS.get(s.kind, s.kind)), rotor=s.job.serial or _("the rotor")
        )
        return who, (_("waiting: {why}").format(why=_(s.waiting)) if s.waiting
                     else _("waiting for the stand"))  # fmt: skip
    return head, sub


def _show_warnings(column: Any, s: Any, _: Language) -> None:
    """The run's warnings and the station's notes, each once, in words (the screen's)."""
    column.clear()
    with column:
        live = s.phase == "measuring"  # a short window: the line of what it waits for says it
        msgs = [w.message for w in s.progress.measurement.warnings
                if not (live and w.code == "short_window")]  # fmt: skip
        msgs += [w.message for w in (s.result.warnings if s.result else ())]
        for msg in dict.fromkeys(msgs):
            ui.label(f"⚠ {_(msg)}").classes("text-h6 text-orange-10")
        for msg in s.notes:
            ui.label(_(msg)).classes("text-h6 text-orange-10")


class _PlaneView:
    """One plane on the Measure screen: its polar plot, its estimate in words, and its
    95 % interval against the goal on a bar (at a scale where both show: on the polar
    plot they are smaller than the dot while the unbalance is large)."""

    def __init__(self, plane: int, _: Language) -> None:
        self.plane, self._ = plane, _
        with ui.column().classes("w-1/2 items-center"):
            self.chart = ui.echart(polar_chart(plane, None, Display.speaking(_), _)).classes(
                "w-full h-96"
            )
            self.text = ui.label().classes("text-h6").mark(f"plane{plane}-live")
            bar = ui.linear_progress(value=0, show_value=False, size="14px")
            self.bar = bar.props("color=primary track-color=grey-4").mark(f"plane{plane}-goal")
            self.goal = ui.label().classes("text-body1").mark(f"plane{plane}-goal-text")

    def show(self, p: Any, units: Display) -> None:
        _ = self._
        self.chart.options.clear()
        self.chart.options.update(polar_chart(self.plane, p, units, _))
        self.chart.update()
        self.text.text = _("plane {i}: {status}").format(
            i=self.plane, status=plane_status(p, units, _)
        )
        self.bar.value = min(1.0, p.goal_kg_m / max(p.radius95_kg_m, 1e-300))
        self.goal.text = _("95 % interval ± {r95}, goal ± {goal} {unit}: {state}").format(
            r95=units.number(p.radius95_kg_m * 1e6),
            goal=units.number(p.goal_kg_m * 1e6),
            unit=units.unbalance_unit,
            state=_("reached") if p.precise else _("not yet"),
        )


def measure_screen(station: Station) -> None:
    """Measure: speed, per plane the live polar plot, the supports, the warnings."""
    _ = words(station)
    with ui.row().classes("w-full items-center gap-4"):  # Stop first: on every screen size

        def stop_run() -> None:
            require(station, "measure", _("stop a run"))
            station.stop()

        stop = ui.button(_("Stop"), on_click=guard(stop_run, None, _)).props(
            "size=xl color=negative"
        )
        stop.mark("stop")
        onward = ui.button(
            _("Go on"),
            on_click=lambda: ui.navigate.to(
                "/check" if station.snapshot().kind == "check" else "/correct"
            ),
        ).props("size=xl color=primary")
        onward.mark("onward")
        head = ui.label().classes("big").mark("measure-head")
    sub = ui.label().classes("text-h6").mark("measure-sub")
    drive_line(station, _)
    with ui.row().classes("w-full no-wrap gap-4"):
        planes = [_PlaneView(i, _) for i in (1, 2)]
    note = ui.label(_(ANGLE_NOTE)).classes("text-body1 text-grey-8")
    warn = ui.column().mark("warnings")
    seen = {"seq": -1}

    def redraw() -> None:
        s = station.snapshot()
        if s.seq == seen["seq"]:
            return
        seen["seq"] = s.seq
        units = _units(station, _)
        stop.set_visibility(s.phase == "measuring")
        onward.set_visibility(s.phase == "done")
        onward.text = _("See the check") if s.kind == "check" else _("Go to the correction")
        if s.progress is None:
            head.text, sub.text = _waiting(s, head.text, sub.text, _)
            return
        n = live_numbers(s.progress)
        verb = {"measuring": _("measuring"), "done": _("measured")}.get(s.phase, _("stopped"))
        head.text = _("{rpm} rpm   {verb} {seconds} s").format(
            rpm=_.number(n["rpm"], 0), verb=verb, seconds=_.number(n["elapsed_s"], 1)
        )
        why = getattr(s.progress, "waiting_for", ())
        sub.text = (
            _("{kind} run of {rotor}; vibration at the supports {a1} and {a2} m/s²").format(
                kind=_(RUN_KINDS.get(s.kind, s.kind)), rotor=s.job.serial or _("the rotor"),
                a1=_.number(n["support1_m_s2"], 3), a2=_.number(n["support2_m_s2"], 3))
            + (f"; {_(s.waiting)}" if s.waiting else "")
            + (_(". Still measuring: waiting for {what}").format(what=_(" and ").join(map(_, why)))
               if why and s.phase == "measuring" else "")
        )  # fmt: skip
        for view, p in zip(planes, planes_live(s.progress, s.tolerance_kg_m), strict=True):
            view.show(p, units)
        _show_warnings(warn, s, _)

    note.set_visibility(True)
    redraw()
    ui.timer(REFRESH_S, redraw)


def _plane_card(station: Station, ins: Any, out: dict[str, Any], _: Language) -> None:
    """One plane's card on the Correct screen: the instruction, then the rotor face."""
    pos = out.get("correction_positions") or {}
    with ui.card().classes("w-1/2").style("min-width: 0").mark(f"correct-plane{ins.plane}"):
        ui.label(ins.headline).classes("text-h6")
        index_line(station, ins.plane, _)
        with ui.row().classes("w-full no-wrap items-start gap-2"):  # words, then face
            with ui.column().classes("gap-0").style("flex: 1 1 auto; min-width: 0"):
                for what, where, stock in ins.lines:
                    ui.label(what).classes("instruction")
                    ui.label(where).classes("text-h6")
                    if stock:
                        ui.label(stock).classes("text-body1 text-grey-8 q-mb-xs")
            svg = face_svg(
                ins.marks,
                positions=int(pos.get("count") or 0),
                position1_deg=float(pos.get("position1_deg") or 0.0),
                action=out["correction_mode"],
                title=_("plane {i}").format(i=ins.plane),
                words=_,
            )
            ui.html(svg, sanitize=False).style("flex: 0 0 13rem; max-width: 13rem")


def correct_screen(station: Station) -> None:
    """Correct: per plane the instruction in large type, on the rotor face."""
    _ = words(station)
    s, latest = station.snapshot(), station.latest()
    if latest is None:
        ui.label(_("Measure the rotor first (Start).")).classes("big")
        return
    out = to_json(latest)
    ui.label(_("Correction of {rotor}").format(rotor=s.job.serial or _("the rotor"))).classes("big")
    with ui.row().classes("w-full no-wrap gap-6"):
        for ins in instructions(out, _):
            _plane_card(station, ins, out, _)
    ui.label(_("{angles}; the faces are drawn {seen}").format(angles=_(ANGLE_NOTE),
                                                             seen=_(SEEN_FROM))).classes(
        "text-body1")  # fmt: skip
    with ui.row().classes("no-wrap gap-4 q-py-sm actions"):  # kept in view (STYLE: sticky)
        turn_buttons(station, _)
        if s.simulated and s.phase == "done":

            def apply() -> None:
                require(station, "correct", _("apply a correction"))
                masses = station.apply_correction()
                notify(_("{n} masses put on the simulated rotor").format(n=len(masses)), "positive")

            ui.button(
                _("Apply the correction (simulated stand)"), on_click=guard(apply, None, _)
            ).props("size=lg color=secondary").mark("apply")
        elif s.phase == "done":

            def confirm() -> None:
                require(station, "correct", _("confirm a correction"))
                station.confirm_applied()
                notify(_("confirmed: the check will calibrate the stand too"), "positive")

            ui.button(_("Applied as shown"), on_click=guard(confirm, None, _)).props(
                "size=lg color=secondary"
            ).mark("applied")

        def check() -> None:
            require(station, "check", _("measure a check run"))
            station.check()

        ui.button(_("Start the check run"), on_click=guard(check, "/measure", _)).props(
            "size=lg color=primary"
        ).mark("check-run")


def check_screen(station: Station) -> None:
    """Check: before and after, URR per plane, the verdict, the certificate."""
    _ = words(station)
    s = station.snapshot()
    if s.kind != "check" or s.result is None:
        ui.label(_("No check run yet: correct the rotor, then start the check run.")).classes("big")
        return
    out = to_json(s.result)
    verdict = check_verdict(out)
    word = {"pass": _("WITHIN TOLERANCE"), "fail": _("NOT WITHIN TOLERANCE"),
            "undecided": _("UNDECIDED: MEASURE LONGER")}.get(
        str(verdict), _("CHECKED (no tolerance set)")
    )  # fmt: skip
    ui.label(f"{s.job.serial or _('rotor')}: {word}").classes(
        "huge " + ("fail" if verdict in ("fail", "undecided") else "pass")
    ).mark("verdict")
    if verdict == "fail":
        ui.label(_("Correct again (Correct shows what is left), then check again.")).classes(
            "text-h5"
        )
    elif verdict == "undecided":
        ui.label(
            _("The residual's interval straddles the limit: check again with a longer run.")
        ).classes("text-h5")
    if out.get("tolerance"):
        t = out["tolerance"]
        ui.label(
            _("Tolerance: {source}; judged in {where}. Rule: {rule}.").format(
                source=_(t["source"]), where=_(t["judged_in"]), rule=_(t["rule"])
            )
        )
        if t.get("allocation"):
            ui.label(_("Allocation: {rule}.").format(rule=_(t["allocation"])))
    names = {
        "plane": _("plane"),
        "before": _("before"),
        "after": _("after"),
        "urr": _("reduction (URR)"),
        "permissible": _("permissible"),
        "verdict": _("verdict"),
    }
    columns = [{"name": k, "label": v, "field": k, "align": "left"}
               for k, v in names.items()]  # fmt: skip
    ui.table(columns=columns, rows=check_rows(out, _)).classes("text-h6").mark("check-table")
    with ui.row().classes("gap-4 q-mt-md"):
        certificate_links(station, s.result, _)

        def next_rotor() -> None:
            require(station, "measure", _("start the next rotor"))
            station.next_rotor()

        ui.button(_("Next rotor"), on_click=guard(next_rotor, "/", _)).props("size=xl").mark("next")


def serve(station: Station, *, host: str, port: int, token: str | None, show: bool,
          names: Sequence[str] = (), certfile: str | None = None,
          keyfile: str | None = None) -> None:  # fmt: skip
    """Serve the station until interrupted: its routes behind their rights, the hosts it
    answers (its bind and ``names``), the security headers, changes from its own pages only,
    the token (if any) on every request, TLS with ``certfile``/``keyfile`` (uvicorn's)."""

    tls = certfile is not None
    add_routes(station)
    add_login_routes(station, secure=tls)
    harden(app, served_hosts(host, names), port, tls)
    if token:
        app.add_middleware(TokenGate, token=token, tls=tls)
    ui.run(
        lambda: frame(station),
        host=host,
        port=port,
        title="Balancing station",
        show=show,
        reload=False,
        show_welcome_message=False,
        reconnect_timeout=10.0,
        ssl_certfile=certfile,
        ssl_keyfile=keyfile,
    )
