"""Fuzz campaign over the command line: damaged logs, hostile messages, full disks, kills.

Every case runs ``python -m trackreplay …`` in its own process (peak memory from ``wait4``) and is
classified:

- ``right``: exit 0 and the right result (a replay's digest and frame count equal the intact log's);
- ``documented``: a documented exit status (docs/exit_codes.md) and at most one ``trackreplay:`` /
  ``warning:`` line on stderr, no traceback;
- defects: ``silent-wrong`` (exit 0, different result), ``traceback``, ``internal`` (exit 70),
  ``timeout``, ``memory`` (peak RSS over the budget), ``undocumented`` (any other status).

``recover`` is also scored on salvage: image messages saved / image messages in chunks the damage
did not touch. Input files and log structures of issue 33 (a CSV field over 128 KB, TOML 1e308 or nested
500 deep, a 50 MB TOML line, JSON nested 200k deep; a log without a summary section, times beyond 2**63,
a channel declared twice) are run once each. Writes docs/reliability.md. Usage:
``python docs/reliability.py [--quick] [--kinds issue33]``.
"""

from __future__ import annotations

import argparse
import json
import os
import random
import resource
import signal
import subprocess
import sys
import tempfile
import time
from collections import Counter, defaultdict
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np
from mcap.reader import make_reader

ROOT = Path(__file__).resolve().parents[1]
DOCUMENTED = {0, 1, 2, 3, 4, 5, 6, 7, 130, 143}
MEMORY_BUDGET_MB = 1500
TIMEOUT_S = 120


@dataclass
class Outcome:
    case: str
    kind: str
    verb: str
    status: int | None
    verdict: str
    peak_mb: float
    seconds: float
    salvage: float | None = None


def run(argv: list[str], *, file_limit: int | None = None, timeout: float = TIMEOUT_S) -> tuple[int | None, str, float, float]:
    """(exit status or None on timeout, stderr, peak RSS MB, seconds) of ``python -m trackreplay ARGV``."""
    def limits() -> None:
        if file_limit is not None:
            signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
            resource.setrlimit(resource.RLIMIT_FSIZE, (file_limit, file_limit))

    start = time.monotonic()
    with tempfile.TemporaryFile() as err:
        proc = subprocess.Popen([sys.executable, "-m", "trackreplay", *argv], stdout=subprocess.DEVNULL, stderr=err,
                                preexec_fn=limits, cwd=ROOT)
        deadline = start + timeout
        status, rusage = None, None
        while time.monotonic() < deadline:
            pid, raw, rusage = os.wait4(proc.pid, os.WNOHANG)
            if pid:
                status = os.waitstatus_to_exitcode(raw)
                break
            time.sleep(0.02)
        else:
            proc.kill()
            _, _, rusage = os.wait4(proc.pid, 0)
        proc.returncode = status if status is not None else -9
        err.seek(0)
        text = err.read().decode("utf-8", "replace")
    return status, text, rusage.ru_maxrss / 1024.0, time.monotonic() - start


def verdict(status: int | None, stderr: str, peak_mb: float, right: bool | None, quiet_ok: bool = False) -> str:
    """``quiet_ok``: the verb reports a partial result on stdout (recover's 1 and 2), not as an error."""
    if status is None:
        return "timeout"
    if peak_mb > MEMORY_BUDGET_MB:
        return "memory"
    if "Traceback" in stderr:
        return "traceback"
    if status == 70:
        return "internal"
    if status not in DOCUMENTED:
        return "undocumented"
    ours = [line for line in stderr.splitlines() if line.startswith(("trackreplay:", "warning:"))]
    if status == 0:
        return "right" if right in (None, True) else "silent-wrong"
    return "documented" if len(ours) >= 1 or quiet_ok else "undocumented"


# --- the logs ----------------------------------------------------------------------------------------
def base_log(folder: Path) -> Path:
    log = folder / "base.mcap"
    status, err, _, _ = run(["synth", "flow-sim1", str(log), "--frames", "51", "--encoding", "jpeg"])
    assert status == 0, err
    return log


def image_counts(path: Path) -> tuple[list[tuple[int, int, int]], int]:
    """((start, end, image messages) per chunk, total images) of an intact log."""
    sys.path.insert(0, str(ROOT))
    from mcap.records import Channel, Message

    from trackreplay.recorder.mcap_scan import ChunkRecords, scan

    data = path.read_bytes()
    with open(path, "rb") as fh:
        summary = make_reader(fh).get_summary()
    images = {cid for cid, ch in summary.channels.items() if ch.topic == "/camera/image"}
    length = {c.chunk_start_offset: c.chunk_length for c in summary.chunk_indexes}
    spans = []
    for item in scan(data):
        if isinstance(item, ChunkRecords):
            n = sum(isinstance(r, Message) and r.channel_id in images for r in item.records)
            spans.append((item.offset, item.offset + length[item.offset], n))
    return spans, sum(n for _, _, n in spans)


def saved_images(path: Path) -> int:
    with open(path, "rb") as fh:
        return sum(1 for _ in make_reader(fh).iter_messages(topics=["/camera/image"]))


def mutations(log: Path, rng: random.Random, n_cut: int, n_flip: int, n_burst: int) -> list[tuple[str, str, bytes, int | None]]:
    """(name, kind, bytes, damaged offset or None) cases."""
    data = log.read_bytes()
    out = []
    for k in range(n_cut):
        cut = rng.randrange(0, len(data))
        out.append((f"cut@{cut}", "truncation", data[:cut], cut))
    for k in range(n_flip):
        pos = rng.randrange(8, len(data))
        b = bytearray(data)
        b[pos] ^= 1 << rng.randrange(8)
        out.append((f"flip@{pos}", "1-bit flip", bytes(b), pos))
    for k in range(n_burst):
        pos = rng.randrange(8, len(data) - 8)
        b = bytearray(data)
        b[pos:pos + 8] = rng.randbytes(8)
        out.append((f"burst@{pos}", "8-byte burst", bytes(b), pos))
    spans, _ = image_counts(log)
    for k, (start, end, _) in enumerate(spans):
        b = bytearray(data)
        b[start:end] = bytes(end - start)
        out.append((f"zero-chunk{k}", "zeroed chunk", bytes(b), start))
    return out


def expected_salvage(kind: str, damaged_at: int | None, spans, total: int) -> int:
    """Images in chunks the damage did not touch (a truncation loses every chunk it cuts or follows)."""
    if damaged_at is None:
        return total
    if kind == "truncation":
        return sum(n for s, e, n in spans if e <= damaged_at)
    return sum(n for s, e, n in spans if not s <= damaged_at < e)


# --- hostile logs, written directly ------------------------------------------------------------------
def hostile_logs(folder: Path) -> list[tuple[str, Path]]:
    sys.path.insert(0, str(ROOT))
    from trackreplay.recorder.image_codec import image_message
    from trackreplay.recorder.writer import LogWriter
    from trackreplay.schemas import topics as T
    from trackreplay.schemas.records import InitRegion, LensEntry, LensTable, PtzReading, init_annotations_pb
    from foxglove_schemas_protobuf.CompressedImage_pb2 import CompressedImage
    from foxglove_schemas_protobuf.RawImage_pb2 import RawImage

    img = np.full((24, 32, 3), 90, np.uint8)

    def frames(log, n=5, times=None):
        for k, t in enumerate(times or [i * 33_000_000 for i in range(n)]):
            log.write(T.CAMERA_IMAGE, image_message(img, "jpeg", t), t)

    ok, jpg = cv2.imencode(".jpg", img)
    huge = bytearray(jpg.tobytes())
    sof = huge.index(b"\xff\xc0")
    huge[sof + 5:sof + 9] = (30000).to_bytes(2, "big") * 2

    cases = {
        "jpeg header 30000x30000": lambda log: log.write(T.CAMERA_IMAGE, CompressedImage(data=bytes(huge), format="jpeg"), 0),
        "raw step 4e9": lambda log: log.write(T.CAMERA_IMAGE, RawImage(width=1, height=2, encoding="mono8", step=4_000_000_000, data=b"abc"), 0),
        "NaN pan": lambda log: (frames(log), log.write(T.PTZ_LENS_TABLE, LensTable(32, 24, (LensEntry(0, 0, 50, 50, 16, 12),)).to_pb(0), 0),
                                [log.write(T.PTZ_ENCODERS, PtzReading(t, float("nan"), 0, 0, 0).to_pb(), t) for t in (0, 10**8)]),
        "empty lens table": lambda log: (frames(log), log.write(T.PTZ_LENS_TABLE, LensTable(32, 24, ()).to_pb(0), 0),
                                         [log.write(T.PTZ_ENCODERS, PtzReading(t, 0, 0, 0, 0).to_pb(), t) for t in (0, 10**8)]),
        "fx = 0": lambda log: (frames(log), log.write(T.PTZ_LENS_TABLE, LensTable(32, 24, (LensEntry(0, 0, 0, 50, 16, 12),)).to_pb(0), 0)),
        "NaN box": lambda log: (frames(log), log.write(T.ANNOTATIONS_INIT, init_annotations_pb([InitRegion(0, 0, float("nan"), 5, 4, 4)], 0), 0)),
        "mark at frame 1e12": lambda log: (frames(log), log.write(T.ANNOTATIONS_INIT, init_annotations_pb([InitRegion(10**12, 0, 5, 5, 4, 4)], 0), 0)),
        "duplicate timestamps": lambda log: frames(log, times=[0, 10, 10, 20]),
        "1-day time gap": lambda log: (frames(log, times=[0, 33_000_000, 66_000_000, 86_400 * 10**9]),
                                       log.write(T.ANNOTATIONS_INIT, init_annotations_pb([InitRegion(0, 0, 16, 12, 4, 4, "ball")], 0), 0)),
        "log time near 2**63": lambda log: (frames(log, times=[0, 33_000_000, 66_000_000, 2**63 - 2]),
                                            log.write(T.ANNOTATIONS_INIT, init_annotations_pb([InitRegion(0, 0, 16, 12, 4, 4, "ball")], 0), 0)),
    }
    out = []
    for name, write in cases.items():
        path = folder / f"hostile-{len(out)}.mcap"
        with LogWriter(path) as log:
            write(log)
        out.append((name, path))
    return out


# --- input files and log structures (issue 33) --------------------------------------------------------
def input_cases(folder: Path, log: Path) -> list[tuple[str, list[str]]]:
    """(name, argv) of text inputs that ended in exit 70 or gigabytes: each must now be exit 2."""
    img = folder / "img"
    img.mkdir(exist_ok=True)
    for i in range(3):
        cv2.imwrite(str(img / f"f{i}.png"), np.full((48, 64, 3), 40 * i, np.uint8))
    huge = "9" * 200_000
    camera_info = ("image_width: 64\nimage_height: 48\ncamera_matrix:\n  rows: 3\n  cols: 3\n"
                   "  data: [50, 0, 32, 0, nan, 24, 0, 0, 1]\n")
    files = {
        "enc.csv": f"t_ns,pan,tilt,zoom,focus\n0,1,2,3,4\n1,{huge},0,1,1\n",
        "marks.csv": f"frame,x,y,w,h,label\n0,1,1,4,4,{huge}\n",
        "big.toml": "[flow]\ncond_max = 1e308\n", "tiny.toml": "[flow]\ncond_max = 1e-300\n",
        "deep.toml": "x = " + "[" * 500 + "]" * 500 + "\n",
        "long.toml": "[flow]\n# " + "x" * 50_000_000 + "\n",
        "deep.json": "[" * 200_000 + "]" * 200_000, "digits.json": '{"width": 64, "height": 48, "K": [' + "9" * 5000 + "]}",
        "camera_info.yaml": camera_info,
        "plane.json": json.dumps({"width": 64, "height": 48, "image_to_ground": [[0, 0, 0]] * 3,
                                  "camera_ground": [0, 0], "camera_height": 5}),
    }
    for name, text in files.items():
        (folder / name).write_text(text)
    out = str(folder / "input-out.mcap")
    record = ["record", out, "--images", str(img), "--fps", "10", "--quiet"]
    return [
        ("CSV field over 128 KB (encoders)", [*record, "--encoders", str(folder / "enc.csv")]),
        ("CSV field over 128 KB (marks)", ["annotate", str(log), "--from-csv", str(folder / "marks.csv"), "--out", out]),
        *[(f"TOML {what}", ["replay", str(log), "--quiet", "--config", str(folder / name)])
          for what, name in (("1e308", "big.toml"), ("1e-300", "tiny.toml"), ("nested 500 deep", "deep.toml"),
                             ("50 MB line", "long.toml"))],
        ("JSON nested 200k deep", [*record, "--calibration", str(folder / "deep.json")]),
        ("JSON 5000-digit number", [*record, "--calibration", str(folder / "digits.json")]),
        ("camera_info with nan", [*record, "--calibration", str(folder / "camera_info.yaml")]),
        ("all-zero image_to_ground", [*record, "--ground-plane", str(folder / "plane.json")]),
        ("--connect http://", ["replay", str(log), "--quiet", "--connect", "http://127.0.0.1:9/proxy"]),
    ]


def _log_mutations():
    """tests/fuzz/log_mutations.py, loaded by path (the tests are not a package)."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("log_mutations", ROOT / "tests" / "fuzz" / "log_mutations.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def structure_logs(folder: Path, log: Path) -> list[tuple[str, Path, bool]]:
    """(name, log, usable as it stands) rewritten from ``log``: streamed without a summary section,
    log times at and beyond 2**63, a channel id declared twice with different schemas."""
    mutations = _log_mutations()

    def rewrite(name: str, streamed: bool = False, chunked: bool = True, time: int | None = None,
                redeclare: bool = False) -> Path:
        return mutations.rewrite(log, folder / f"structure-{name}.mcap", streamed=streamed, chunked=chunked, time=time,
                                 redeclare=redeclare, library="reliability")

    return [("streamed, no summary", rewrite("streamed", streamed=True), True),
            ("streamed, no chunks", rewrite("unchunked", streamed=True, chunked=False), True),
            ("log time 2**63", rewrite("t63", time=2**63), False),
            ("log time -1 as unsigned", rewrite("tneg", time=2**64 - 1), False),
            ("channel declared twice", rewrite("twice", redeclare=True), True)]


def issue33(folder: Path, log: Path, intact: dict) -> list[Outcome]:
    outcomes = []
    for name, argv in input_cases(folder, log):
        s, err, mb, sec = run(argv)
        ok = s == 2 and len(err.strip().splitlines()) >= 1 and "Traceback" not in err
        outcomes.append(Outcome(name, "input file", argv[0], s, "documented" if ok else verdict(s, err, mb, False), mb, sec))
    for name, path, usable in structure_logs(folder, log):
        s, err, mb, sec = run(["info", str(path)])
        outcomes.append(Outcome(name, "log structure", "info", s, verdict(s, err, mb, None if usable else False), mb, sec))
        summary = folder / f"{path.stem}.json"
        s, err, mb, sec = run(["replay", str(path), "--quiet", "--summary", str(summary)])
        right = (json.loads(summary.read_text())["digest"] == intact["digest"]) if s == 0 and usable else (None if s else False)
        outcomes.append(Outcome(name, "log structure", "replay", s, verdict(s, err, mb, right), mb, sec))
        s, err, mb, sec = run(["recover", str(path), str(folder / f"{path.stem}.fixed.mcap")])
        complete = s == 0 if usable else None  # a usable log is complete, not a partial salvage
        outcomes.append(Outcome(name, "log structure", "recover", s, verdict(s, err, mb, complete, quiet_ok=s in (1, 2)), mb, sec))
    return outcomes


# --- the campaign ------------------------------------------------------------------------------------
def campaign(quick: bool, kinds: set[str] = frozenset({"damage", "hostile", "disk", "issue33"})) -> tuple[list[Outcome], dict]:
    rng = random.Random(0)
    folder = Path(tempfile.mkdtemp(prefix="trackreplay-fuzz-"))
    log = base_log(folder)
    spans, total = image_counts(log)
    intact_summary = folder / "intact.json"
    run(["replay", str(log), "--quiet", "--summary", str(intact_summary)])
    intact = json.loads(intact_summary.read_text())
    n = (20, 30, 10) if quick else (120, 200, 60)
    cases = mutations(log, rng, *n) if "damage" in kinds else []
    outcomes: list[Outcome] = issue33(folder, log, intact) if "issue33" in kinds else []

    def one(case) -> list[Outcome]:
        name, kind, data, at = case
        path = folder / f"{name}.mcap"
        path.write_bytes(data)
        results = []
        s, err, mb, sec = run(["info", str(path)])
        results.append(Outcome(name, kind, "info", s, verdict(s, err, mb, None if s else data == log.read_bytes()), mb, sec))
        summary = folder / f"{name}.json"
        s, err, mb, sec = run(["replay", str(path), "--quiet", "--summary", str(summary)])
        right = None
        if s == 0:
            got = json.loads(summary.read_text())
            right = (got["digest"], got["frames"]) == (intact["digest"], intact["frames"])
        results.append(Outcome(name, kind, "replay", s, verdict(s, err, mb, right), mb, sec))
        out = folder / f"{name}.fixed.mcap"
        s, err, mb, sec = run(["recover", str(path), str(out)])
        salvage = None
        if out.exists():
            expected = expected_salvage(kind, at, spans, total)
            salvage = min(1.0, saved_images(out) / expected) if expected else None
        results.append(Outcome(name, kind, "recover", s, verdict(s, err, mb, None, quiet_ok=s in (1, 2)), mb, sec, salvage))
        return results

    with ThreadPoolExecutor(2) as pool:
        for rows in pool.map(one, cases):
            outcomes.extend(rows)

    # Success is right only where the log is usable as it stands (a long time gap is data, not damage).
    usable = {"1-day time gap", "log time near 2**63"}
    for name, path in hostile_logs(folder) if "hostile" in kinds else ():
        for tracker in ("flow", "golf"):
            s, err, mb, sec = run(["replay", str(path), "--quiet", "--tracker", tracker], timeout=60)
            right = None if name in usable else (None if s else False)
            outcomes.append(Outcome(f"{name} ({tracker})", "hostile message", "replay", s, verdict(s, err, mb, right), mb, sec))

    # Full disk for every writing verb.
    for verb, argv, limit in [] if "disk" not in kinds else [
        ("synth", ["synth", "flow-sim1", str(folder / "full-synth.mcap"), "--frames", "51"], 300_000),
        ("replay --export", ["replay", str(log), "--quiet", "--export", str(folder / "full.parquet")], 2_000),
        ("replay --rrd", ["replay", str(log), "--quiet", "--rrd", str(folder / "full.rrd")], 100_000),
        ("recover", ["recover", str(log), str(folder / "full-recover.mcap")], 50_000),
        ("annotate", ["annotate", str(log), "--frame", "0", "--box", "1,1,4,4", "--out", str(folder / "full-ann.mcap")], 50_000),
    ]:
        s, err, mb, sec = run(argv, file_limit=limit)
        ok = s == 5 and "Traceback" not in err
        outcomes.append(Outcome(verb, "full disk", verb.split()[0], s, "documented" if ok else verdict(s, err, mb, False), mb, sec))
    return outcomes, {"images": total, "chunks": len(spans), "bytes": log.stat().st_size}


def write_report(outcomes: list[Outcome], meta: dict, path: Path) -> None:
    good = {"right", "documented"}
    by = defaultdict(Counter)
    for o in outcomes:
        by[(o.kind, o.verb)][o.verdict] += 1
    verdicts = ["right", "documented", "silent-wrong", "traceback", "internal", "timeout", "memory", "undocumented"]
    lines = [
        "# Reliability: fuzz campaign",
        "",
        "Generated by `python docs/reliability.py` (fixed seed). Each case runs the real command line in its",
        "own process; the base log is `synth flow-sim1 --frames 51 --encoding jpeg` "
        f"({meta['bytes']} bytes, {meta['images']} images in {meta['chunks']} chunks). Classes as in the script's docstring;",
        "everything right of `documented` is a defect. Exit statuses: [exit_codes.md](exit_codes.md).",
        "",
        "| damage | verb | cases | " + " | ".join(verdicts) + " | peak RSS max (MB) |",
        "|---|---|---|" + "---|" * len(verdicts) + "---|",
    ]
    for (kind, verb), counts in sorted(by.items()):
        peak = max(o.peak_mb for o in outcomes if (o.kind, o.verb) == (kind, verb))
        lines.append(f"| {kind} | {verb} | {sum(counts.values())} | " + " | ".join(str(counts.get(v, 0)) for v in verdicts)
                     + f" | {peak:.0f} |")
    lines += ["", "## Salvage by `recover`", "",
              "Image messages saved / image messages in chunks the damage did not touch (a truncation loses the chunk it cuts).",
              "", "| damage | cases | mean salvage | cases with 100 % |", "|---|---|---|---|"]
    rec = defaultdict(list)
    for o in outcomes:
        if o.verb == "recover" and o.salvage is not None:
            rec[o.kind].append(o.salvage)
    for kind, values in sorted(rec.items()):
        lines.append(f"| {kind} | {len(values)} | {100 * np.mean(values):.1f} % | {sum(v >= 1.0 for v in values)} |")
    hostile = [o for o in outcomes if o.kind == "hostile message"]
    if hostile:
        lines += ["", "## Hostile messages (replay)", "", "| message | exit | verdict | peak RSS (MB) |", "|---|---|---|---|"]
        lines += [f"| {o.case} | {o.status} | {o.verdict} | {o.peak_mb:.0f} |" for o in hostile]
    bad = [o for o in outcomes if o.verdict not in good]
    lines += ["", f"Defects: {len(bad)} of {len(outcomes)} runs."]
    lines += [f"- {o.verb} on {o.case}: {o.verdict} (exit {o.status})" for o in bad[:30]]
    lines += ["", f"Machine: {os.cpu_count()} cores, Python {sys.version.split()[0]}; "
              f"slowest run {max(o.seconds for o in outcomes):.1f} s.", ""]
    path.write_text("\n".join(lines))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="a small budget (about 3 minutes on 2 cores)")
    parser.add_argument("--out", type=Path, default=ROOT / "docs" / "reliability.md")
    parser.add_argument("--kinds", default="damage,hostile,disk,issue33",
                        help="which cases: damage (bit flips, truncation...), hostile (messages), disk (full), issue33 "
                             "(input files and log structures); a subset is printed, docs/reliability.md kept")
    args = parser.parse_args()
    kinds = set(args.kinds.split(","))
    outcomes, meta = campaign(args.quick, kinds)
    out = args.out if kinds >= {"damage", "hostile", "disk", "issue33"} else Path(tempfile.mkdtemp()) / "subset.md"
    write_report(outcomes, meta, out)
    print(out.read_text())


if __name__ == "__main__":
    main()
