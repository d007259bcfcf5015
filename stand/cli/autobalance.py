"""Where a ball balancer on the rotor balances it: the windows of speed, and the state it
settles in (:mod:`stand.solve.autobalance`)."""

from __future__ import annotations

import argparse
import cmath
import math
from dataclasses import replace
from typing import Any

from stand.actions import archive_run
from stand.archive import url_for
from stand.cli.common import ACCEPTANCE_EXIT, actor_of, add_actor_arguments, add_archive_argument
from stand.cli.format import ANGLE_NOTE, dump_json
from stand.config import Config, load_config, validate
from stand.config.autobalancer import AutobalancerTable, check_autobalancer
from stand.config.rocker import load_rocker
from stand.config.typed import parse_rpm, parse_unbalance, positive_float
from stand.errors import UsageError
from stand.field.balancer import balancer_test
from stand.sim import load_scene
from stand.sim.scene import unbalance_kg_m
from stand.solve.autobalance import predict
from stand.solve.rocker import predict_rocker

BALL_KEYS = ("plane", "balls", "ball_g", "radius_mm")


def _plane_unbalance(text: str) -> tuple[int, float, float]:
    """``PLANE:G_MM@DEG``."""
    plane, sep, rest = text.partition(":")
    if not sep or plane not in ("1", "2"):
        raise argparse.ArgumentTypeError(f"expected PLANE:G_MM@DEG (e.g. 1:5000@30), got {text!r}")
    return (int(plane), *parse_unbalance(rest))


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "what", nargs="*", metavar="test RUN",
        help="test RUN...: the acceptance test of a rotor with a ball balancer from its "
        "starts (runs in order, with --config): residuals, onset, verdict; archived",
    )  # fmt: skip
    where = p.add_mutually_exclusive_group(required=True)
    where.add_argument("--config", metavar="CFG", help="the stand's config ([autobalancer])")
    where.add_argument("--scene", metavar="SCENE", help="a scene: its stand and unbalance")
    where.add_argument(
        "--rocker", metavar="FILE.toml",
        help="a grinder on a rocker ([rocker] table, the seeds' symbols): its onset, "
        "resonances, damping and cutting bounds",
    )  # fmt: skip
    p.add_argument("--plane", type=int, choices=(1, 2), help="the plane of the balls' race")
    p.add_argument("--balls", type=int, help="how many balls (2 or more)")
    p.add_argument("--ball-g", type=positive_float, help="each ball's mass [g]")
    p.add_argument("--radius-mm", type=positive_float, help="the balls' running radius [mm]")
    p.add_argument("--rpm", type=parse_rpm, help="the speed to judge the balanced state at")
    p.add_argument(
        "--unbalance", action="append", type=_plane_unbalance, metavar="PLANE:G_MM@DEG",
        help="the rotor's unbalance in a plane, at an angle from the reference mark against "
        "the direction of rotation (repeatable; default with --scene: the scene's)",
    )  # fmt: skip
    p.add_argument("--max-rpm", type=parse_rpm, help="seek windows up to this speed")
    p.add_argument(
        "--moved-deg", type=float, default=180.0,
        help="test: how far the test unbalance moves from one start to the next [deg]",
    )  # fmt: skip
    add_archive_argument(p)
    add_actor_arguments(p)
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--no-archive", action="store_true", help="test: do not archive the starts")


def _table(args: argparse.Namespace, cfg: Config, source: str) -> AutobalancerTable:
    """The config's ``[autobalancer]`` with the options over it (or the options alone)."""
    given = {k: getattr(args, k) for k in BALL_KEYS if getattr(args, k) is not None}
    base = cfg.autobalancer.model_dump() if cfg.autobalancer is not None else {}
    missing = [k for k in BALL_KEYS if k not in {**base, **given}]
    if missing:
        flags = ", ".join("--" + k.replace("_", "-") for k in missing)
        raise UsageError(f"stand autobalance: {source} has no [autobalancer]: give {flags}")
    return validate(AutobalancerTable, {**base, **given}, source, prefix="autobalancer.")


def run(args: argparse.Namespace) -> int:
    if args.what:
        return _test(args)
    if args.rocker:
        return _rocker(args)
    U: list[complex] | None = None
    if args.scene:
        scene, params, source = load_scene(args.scene)
        cfg = scene.config()
        q, phi = unbalance_kg_m(scene)
        U = [cmath.rect(m, -math.radians(a)) for m, a in zip(q, phi, strict=True)]
    else:
        cfg, params = load_config(args.config)
        source = args.config
    if args.unbalance:
        U = [0j, 0j]
        for plane, g_mm, deg in args.unbalance:
            U[plane - 1] += cmath.rect(g_mm * 1e-6, -math.radians(deg))
    table = _table(args, cfg, source)
    check_autobalancer(table, params, source)  # the options too, against the rotor
    doc = predict(params, table, rpm=args.rpm, unbalance_kg_m=U if args.rpm else None,
                  max_rpm=args.max_rpm)  # fmt: skip
    if args.json:
        dump_json(doc)
        return 0
    _print(doc)
    return 0


def _rocker(args: argparse.Namespace) -> int:
    stray = [f"--{k.replace('_', '-')}" for k in (*BALL_KEYS, "unbalance", "max_rpm")
             if getattr(args, k) is not None]  # fmt: skip
    if stray:
        raise UsageError(f"stand autobalance --rocker: {', '.join(stray)} belong to a stand; "
                         "the rocker file says it all")  # fmt: skip
    doc = predict_rocker(load_rocker(args.rocker), rpm=args.rpm)
    if args.json:
        dump_json(doc)
    else:
        _print_rocker(doc)
    return 0


def _print(doc: dict[str, Any]) -> None:
    n = doc["balls"]
    print(f"{n} balls of {doc['ball_g']:g} g on {doc['radius_mm']:g} mm in plane {doc['plane']}: "
          f"capacity {doc['capacity_g_mm']:.0f} g mm")  # fmt: skip
    nat = ", ".join(f"{x:.0f}" for x in doc["natural_rpm"])
    anti = doc["antiresonance_rpm"]
    print(f"natural speeds {nat} rpm; the race plane's antiresonance "
          + ("none" if anti is None else f"{anti:.0f} rpm"))  # fmt: skip
    for lo, hi in doc["windows_rpm"]:
        print(f"  the balls balance from {lo:.0f} rpm "
              + (f"to {hi:.0f} rpm" if hi is not None else "up (no upper edge)"))  # fmt: skip
    b = doc["balanced"]
    if b is None:
        return
    if not b["in_window"]:
        print(f"at {b['rpm']:g} rpm: in no window: {b['note']}")
        return
    share = f"{100 * b['capacity_ratio']:.0f} % of capacity"
    print(f"at {b['rpm']:g} rpm the balls make {b['balls_g_mm']:.1f} g mm at "
          f"{b['balls_angle_deg']:.1f} deg ({share})")  # fmt: skip
    if b["ball_angles_deg"]:
        print("  balls at " + ", ".join(f"{a:.1f}" for a in b["ball_angles_deg"]) + " deg")
    else:
        print(f"  {b['ball_angles_note']}")
    for r in b["residual"]:
        print(f"  the stand then measures plane {r['plane']}: {r['unbalance_g_mm']:.1f} g mm "
              f"at {r['angle_deg']:.1f} deg")  # fmt: skip
    if "note" in b:
        print(f"  {b['note']}")
    print(f"({ANGLE_NOTE})")


def _print_rocker(doc: dict[str, Any]) -> None:
    """Print :func:`stand.solve.rocker.predict_rocker`'s document."""
    print(f"J_O {doc['J_O_kg_m2']:.6g} kg m^2, omega0 {doc['omega0_rad_s']:.4g} rad/s")
    print(f"the balls balance above {doc['onset_rpm']:.0f} rpm (omega > omega0), away from "
          "the forced resonances at "
          + ", ".join(f"{x:.0f}" for x in doc["forced_resonances_rpm"]) + " rpm")  # fmt: skip
    state = "suppressed" if doc["parametric_suppressed"] else "NOT suppressed"
    floquet = (f"{doc['floquet_h_min_n_s_m']:.4g} N s/m, sigma* "
               f"{doc['floquet_sigma_threshold']:.4f}")  # fmt: skip
    print(f"parametric resonance at {doc['parametric_rpm']:.0f} rpm: {state} (the hinge's "
          f"damping must exceed {doc['h_min_n_s_m']:.4g} N s/m; Floquet at the rocker's eps: "
          f"{floquet})")  # fmt: skip
    share = f"{100 * doc['capacity_ratio']:.0f} % of the balls' capacity"
    if doc["can_balance"]:
        print(f"the disc's largest unbalance is {share}: the balls can cancel it")
    else:
        print(f"the disc's largest unbalance is {share}: beyond what the balls can cancel")
    if doc.get("ball_angles_deg"):
        print("  balls at " + ", ".join(f"{a:.1f}" for a in doc["ball_angles_deg"])
              + " deg from the unbalance")  # fmt: skip
    elif doc.get("ball_angles_note"):
        print(f"  {doc['ball_angles_note']}")
    cut = doc["cutting"]
    if cut is not None:
        print(
            f"cutting: omega0 {cut['omega0_cutting_rad_s']:.4g} rad/s at theta "
            f"{cut['theta_rad']:.4f} rad, at most {cut['omega0_star_rad_s']:.4g} rad/s "
            f"(worst theta {cut['worst_theta_exact_rad']:.4f} rad); "
            + ("the disc presses" if cut["pressing"] else "the moment does not press")
        )
        if cut["c_n_max_exact_n_m"] is not None:
            print(f"  the work's contact stiffness must stay below {cut['c_n_max_exact_n_m']:.4g}"
                  f" N/m (series: {cut['c_n_max_series_n_m']:.4g})")  # fmt: skip
    at = doc["at"]
    if at is not None:
        verdict = "the balls balance" if at["balances"] else "the balls do not balance"
        print(f"at {at['rpm']:g} rpm {verdict} (criterion {at['criterion_m']:.3g} m); 2x "
              f"amplitude {at['amplitude_2x_rad']:.3g} rad")  # fmt: skip


def _test(args: argparse.Namespace) -> int:
    """``stand autobalance test RUN... --config CFG``: the balancer's acceptance test."""
    if args.what[0] != "test" or len(args.what) < 2:
        raise UsageError("stand autobalance: the only action is test RUN... (one or more runs)")
    if not args.config:
        raise UsageError("stand autobalance test: give --config CFG (with its [autobalancer])")
    stray = [f"--{k.replace('_', '-')}" for k in (*BALL_KEYS, "rpm", "max_rpm")
             if getattr(args, k) is not None]  # fmt: skip
    if stray:
        raise UsageError(f"stand autobalance test: {', '.join(stray)}: the test takes the "
                         "balancer from --config and the speed from the runs")  # fmt: skip
    if not math.isfinite(args.moved_deg):
        raise UsageError(f"--moved-deg: a number of degrees, got {args.moved_deg}")
    cfg, params = load_config(args.config)
    first = None
    if args.unbalance:
        first = [0j, 0j]
        for plane, g_mm, deg in args.unbalance:
            first[plane - 1] += cmath.rect(g_mm * 1e-6, -math.radians(deg))
    doc, starts = balancer_test(args.what[1:], args.config, cfg, params, first, args.moved_deg)
    doc["certificate"] = certificate_line(doc)
    if not args.no_archive:
        url = url_for(args.archive, cfg)
        actor = actor_of(args, url)
        doc["archived"] = []
        for k, s in enumerate(starts):
            job = replace(s.result.provenance.job, note=f"balancer test: {doc['line']} "
                          f"(start {k + 1} of {len(starts)})")  # fmt: skip
            result = replace(s.result, provenance=replace(s.result.provenance, job=job))
            doc["archived"].append(archive_run(result, url, actor, config=args.config))
    if args.json:
        dump_json(doc)
    else:
        _print_test(doc)
    return ACCEPTANCE_EXIT[doc["overall"]]


def certificate_line(doc: dict[str, Any]) -> str:
    """The test's one line for a certificate."""
    who = f"serial {doc['serial']}" if doc["serial"] else "the rotor"
    parts = [f"balancer test of {who}: {doc['line']}, {doc['starts_n']} start(s) at "
             f"{doc['rpm']:.0f} rpm"]  # fmt: skip
    for r in doc["residual"]:
        pred = r["predicted_mean_g_mm"]
        parts.append(f"plane {r['plane']} residual mean {r['mean_g_mm']:.1f} g mm, 95th "
                     f"percentile {r['p95_g_mm']:.1f}"
                     + ("" if pred is None else f" (predicted {pred:.1f})"))  # fmt: skip
    on, edge = doc["onset_rpm"], doc["window_edge_rpm"]
    if on is not None and edge is not None:
        parts.append(f"onset {on['mean']:.0f} rpm against the window's edge at {edge:.0f}")
    return "; ".join(parts)


def _print_test(doc: dict[str, Any]) -> None:
    for s in doc["starts"]:
        res = ", ".join(f"plane {r['plane']} {r['unbalance_g_mm']:.1f} +- "
                        f"{r['uncertainty_g_mm']:.1f} g mm at {r['angle_deg']:.1f} deg"
                        for r in s["residual"])  # fmt: skip
        onset = "" if s["onset_rpm"] is None else f", onset {s['onset_rpm']:.0f} rpm"
        print(f"{s['run']}: {s['rpm']:.0f} rpm{onset}: {res}")
    for note in doc["notes"]:
        print(f"  {note}")
    print(doc["certificate"])
    if "archived" in doc:
        print("archived as run(s) " + ", ".join(str(i) for i in doc["archived"]))
    print(f"({ANGLE_NOTE})")
