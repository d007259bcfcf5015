"""Long runs: `stand solve` against a minimal numpy parse-and-fit of the same file.

    .venv/bin/python tests/bench/bench_long.py [--seconds 60 600 3600] [--repeat 5]

For each length a demo run (two nodes at 4 kHz) is written as an .h5 run
file and as a candump .log.  Each is solved in a fresh process by `stand
solve` and by the *reference* below (``--reference FILE``): read, decode
SAMPLES and MARK frames of nodes 1 and 2, shaft angle by linear
interpolation between edges, one least-squares 1x fit per node.  The
reference does none of the product's checks (gate, side-band noise, block
scatter, speed-squared columns, 2x/3x, intervals): it is the floor a
product that reads the same bytes cannot beat.

The two are run in turns (stand, reference, stand, ...) so that the
machine's drifting speed falls on both; the project's modules are compiled
to bytecode first, as an installed package has them (the reference's numpy
and h5py have theirs).  Printed, best of the repeats: wall time, CPU time
(user + system, the forked child's included), the process's peak resident
memory (MiB), and the peak of the whole process tree (``stand solve`` forks
a child for node 2 of a long run) as the sum of the processes'
proportional set sizes, sampled every 5 ms in one more run; the time ratio
of the best times, and the median of the ratios of the turns.  A 3 s run
gives what a solve costs before its data.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

STAND = str(Path(sys.executable).with_name("stand"))
EPOCH_S = 1763799999.0
"""Host stamps start here (2025-11-22, epoch seconds): 16 digits with microseconds."""
HEX = np.full(256, 255, np.uint8)
for _k, _c in enumerate(b"0123456789ABCDEF"):
    HEX[_c] = _k
    HEX[bytes([_c]).lower()[0]] = _k


def parse_candump(path: str, block: int = 1 << 23) -> tuple[np.ndarray, np.ndarray]:
    """Vectorised candump parse: (can_id, data (n, 8)) of ``(ts) iface ID#DATA`` lines.

    In blocks of whole lines (bounded memory).  Lines are grouped by length;
    within a group every line has the same layout (checked), so each field is
    a column slice of one 2-D byte array.
    """
    raw = np.fromfile(path, np.uint8)
    ids, datas = [], []
    at = 0
    while at < raw.size:
        cut = min(at + block, raw.size)
        if cut < raw.size:
            cut += int(np.flatnonzero(raw[cut - 1 :] == 10)[0])
        i, d = _parse_block(raw[at:cut])
        ids.append(i)
        datas.append(d)
        at = cut
    return np.concatenate(ids), np.concatenate(datas)


def _parse_block(raw: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    nl = np.flatnonzero(raw == 10)
    starts = np.concatenate(([0], nl[:-1] + 1))
    lens = nl - starts
    ids, datas, order = [], [], []
    for L in np.unique(lens):
        rows = np.flatnonzero(lens == L)
        block = raw[starts[rows][:, None] + np.arange(L)]
        first = block[0].tobytes()
        h = first.index(b"#")
        sp = first.rindex(b" ", 0, h)
        assert (block[:, h] == ord("#")).all() and (block[:, sp] == ord(" ")).all()
        idx = HEX[block[:, sp + 1 : h]].astype(np.uint32)
        can_id = np.zeros(len(rows), np.uint32)
        for k in range(idx.shape[1]):
            can_id = can_id * 16 + idx[:, k]
        end = first.find(b" ", h)  # python-can writes a trailing " R" (received)
        nib = HEX[block[:, h + 1 : end if end > 0 else L]]
        data = np.zeros((len(rows), 8), np.uint8)
        nb = nib.shape[1] // 2
        data[:, :nb] = nib[:, 0::2] * 16 + nib[:, 1::2]
        ids.append(can_id)
        datas.append(data)
        order.append(rows)
    o = np.argsort(np.concatenate(order), kind="stable")
    return np.concatenate(ids)[o], np.concatenate(datas)[o]


def reference(path: str) -> dict[str, float]:
    """Read, decode nodes 1 and 2, angle by interpolation, one 1x fit per node."""
    if path.endswith(".h5"):
        import h5py

        with h5py.File(path, "r") as f:
            can_id = f["frames/can_id"][:]
            data = f["frames/data"][:, :8]
    else:
        can_id, data = parse_candump(path)
    out = {}
    for node in (1, 2):
        s = can_id == 0x100 + node
        seq = data[s, 0:2].copy().view("<u2")[:, 0].astype(np.int64)
        frame = np.concatenate(([0], np.cumsum(np.diff(seq) % 65536))) + seq[0]
        counts = data[s, 2:8].copy().view("<i2").astype(np.float64) * 1e-4
        index = (3 * frame[:, None] + np.arange(3)).ravel()
        m = can_id == 0x180 + node
        mseq = data[m, 0:2].copy().view("<u2")[:, 0].astype(np.int64)
        mframe = frame[0] + (mseq - seq[0]) % 65536
        pos = 3 * mframe + data[m, 2] + data[m, 3:5].copy().view("<u2")[:, 0] / 65536
        inside = (index >= pos[0]) & (index <= pos[-1])
        theta = 2 * np.pi * np.interp(index[inside], pos, np.arange(len(pos)))
        a = counts.ravel()[inside]
        X = np.column_stack((np.cos(theta), np.sin(theta), np.ones(len(a))))
        coef = np.linalg.solve(X.T @ X, X.T @ a)
        out[f"node{node}"] = float(np.hypot(coef[0], coef[1]))
    return out


def timed(argv: list[str]) -> tuple[float, float, float]:
    """Wall time [s], CPU time [s] and peak resident memory [MiB] of a fresh process."""
    t0 = time.perf_counter()
    r = subprocess.run(
        ["/usr/bin/time", "-f", "%U %S %M", *argv], capture_output=True, text=True, check=True
    )
    wall = time.perf_counter() - t0
    user, system, rss = r.stderr.strip().splitlines()[-1].split()
    return wall, float(user) + float(system), int(rss) / 1024


def _pss_kib(pid: int) -> int:
    try:
        with open(f"/proc/{pid}/smaps_rollup") as f:
            return next((int(ln.split()[1]) for ln in f if ln.startswith("Pss:")), 0)
    except OSError:
        return 0


def _children(pid: int) -> list[int]:
    try:
        with open(f"/proc/{pid}/task/{pid}/children") as f:
            return [int(c) for c in f.read().split()]
    except OSError:
        return []


def tree_peak(argv: list[str]) -> float:
    """Peak of the process tree's summed proportional set size [MiB], sampled every 5 ms."""
    p = subprocess.Popen(argv, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    peak = 0
    while p.poll() is None:
        peak = max(peak, sum(_pss_kib(q) for q in [p.pid, *_children(p.pid)]))
        time.sleep(0.005)
    return peak / 1024


def compile_bytecode() -> None:
    """The project's modules as bytecode, as an installed package has them."""
    import compileall

    import stand

    root = Path(stand.__file__).parent
    for folder in (root, root.parent / "drivers", root.parent / "calib"):
        compileall.compile_dir(str(folder), quiet=1)


def make_run(tmp: Path, seconds: float) -> tuple[Path, Path, Path]:
    from stand.config import config_toml
    from stand.drivers import Recording, write_recording
    from stand.drivers.runs.logs import write_log
    from stand.sim import load_scene, simulate

    sc, p, _ = load_scene("demo")
    data = sc.model_dump()
    data["run"]["seconds"] = seconds
    scene = type(sc).model_validate(data, strict=False)
    frames = simulate(scene, p).frames
    # stamped as candump -l and python-can's logger stamp them: epoch seconds, microseconds
    frames = type(frames)(frames.t_s + EPOCH_S, frames.can_id, frames.dlc, frames.data,
                          frames.flags)  # fmt: skip
    cfg = tmp / "cfg.toml"
    cfg.write_text(config_toml(scene.config()))
    h5 = tmp / f"run{seconds:g}.h5"
    write_recording(Recording("bench", frames, {"config_toml": cfg.read_text()}), h5)
    log = tmp / f"run{seconds:g}.log"
    write_log(frames, log)
    return h5, log, cfg


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--seconds", type=float, nargs="+", default=[60.0, 600.0])
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--reference", metavar="FILE", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.reference:
        print(json.dumps(reference(args.reference)))
        return
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    compile_bytecode()
    tmp = Path(tempfile.mkdtemp())
    print(
        "| run | `stand solve` | CPU | peak | tree peak | reference | CPU | peak "
        "| time ratio (median) | memory ratio |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|")
    try:
        for seconds in args.seconds:
            h5, log, cfg = make_run(tmp, seconds)
            for path in (h5, log):
                cmd = [STAND, "solve", str(path), "--json"]
                if path.suffix == ".log":
                    cmd += ["--config", str(cfg)]
                ref = [sys.executable, __file__, "--reference", str(path)]
                pairs = [(timed(cmd), timed(ref)) for _ in range(args.repeat)]
                s = min((a for a, _ in pairs), key=lambda x: x[0])
                r = min((b for _, b in pairs), key=lambda x: x[0])
                median = sorted(a[0] / b[0] for a, b in pairs)[len(pairs) // 2]
                tree = tree_peak(cmd)
                print(
                    f"| {seconds:g} s {path.suffix} | {s[0]:.2f} s | {s[1]:.2f} s | "
                    f"{s[2]:.0f} MiB | {tree:.0f} MiB | {r[0]:.2f} s | {r[1]:.2f} s | "
                    f"{r[2]:.0f} MiB | {s[0] / r[0]:.1f}x ({median:.1f}x) | "
                    f"{max(s[2], tree) / r[2]:.1f}x |",
                    flush=True,
                )
            h5.unlink()
            log.unlink()
    finally:
        shutil.rmtree(tmp)


if __name__ == "__main__":
    main()
