"""The corpus manifest of ``trackreplay evaluate``: a TOML file of ``[[case]]`` tables (docs/evaluate.md).

Each case names one source (``video``, ``images`` with ``fps``, ``log`` or ``synth`` with ``seed``),
its truth (a file in a format ``record --groundtruth`` reads; synthetic scenes and logs carry their
own) and how to start the trackers from it. Paths are relative to the manifest's folder, or to
``[corpus] data_root`` when the manifest gives one (itself relative to the manifest;
``TRACKREPLAY_DATA_ROOT`` overrides it, in every manifest that gives one), so a corpus of public recordings kept outside the
repository is found where the machine keeps it. A case whose files are missing is *skipped* (one
line), not failed. Unknown keys are refused in one sentence naming the file, the case and the keys
this version knows.
"""

from __future__ import annotations

import math
import os
import tomllib
from dataclasses import dataclass, fields
from pathlib import Path
from typing import Any

from trackreplay.replay.core import registry
from trackreplay.replay.runs.scenes import scene_config
from trackreplay.schemas.errors import SourceError

DATA_ROOT_ENV = "TRACKREPLAY_DATA_ROOT"
TARGETS = ("box", "point", "objects")
# What a target kind is scored with and, unless a case names its trackers, what runs on it:
# boxes -> the colour PF and the flow tracker (both report a box); a point (a ball) -> golf;
# several objects with identities -> groups (CLEAR MOT, IDF1, HOTA).
DEFAULT_TRACKERS = {"box": ("colorpf", "flow"), "point": ("golf",), "objects": ("groups",)}
# The kind of target each synthetic scene's truth describes (the scene writes its own truth).
SYNTH_TARGETS = {"flow-": "box", "golf-": "point", "colorpf-": "box", "groups-": "objects"}
# Formats whose rows are points (no box) or several tracked objects; the rest are boxes.
POINT_FORMATS = ("points", "tracknet", "reference")
OBJECT_FORMATS = ("mot",)
MARK_MODES = ("truth", "log")
SOURCES = ("video", "images", "log", "synth")


@dataclass(frozen=True)
class Case:
    """One ``[[case]]`` of a manifest, its paths resolved."""

    name: str
    video: Path | None = None
    images: Path | None = None
    log: Path | None = None
    synth: str | None = None  # a `trackreplay synth` scene
    seed: int = 0  # the synthetic scene's seed
    synth_options: tuple[tuple[str, Any], ...] = ()  # the scene's config fields, e.g. frames = 20
    fps: float | None = None  # images: required; video: overrides the file's rate
    truth: Path | None = None
    truth_format: str = "auto"
    truth_first_frame: int = 0  # the recorded frame the truth's first line describes (record --gt-first-frame)
    target: str = ""  # box | point | objects ("" until resolved: from the scene or the truth's format)
    object: int | None = None  # the truth's object id to start from and score (default: the most visible)
    start: tuple[int, ...] = ()  # frames marked from the truth (several: re-marks); () = first usable truth frame
    trackers: tuple[str, ...] = ()  # default: DEFAULT_TRACKERS[target]
    mark_size: float = 12.0  # side (px) of the box marked round a point truth
    marks: str = "truth"  # truth: marks from the truth (the log's own removed); log: the log's own marks
    label: str = "target"  # the marks' label (the flow tracker reads only `target`)
    baseline: bool = True  # OpenCV CSRT beside the trackers on box cases
    # the fixed camera's ground plane: "" none, "truth" fitted to the truth's feet and ground positions
    # (record --ground-plane-from-truth), else a ground-plane JSON file (record --ground-plane)
    ground_plane: str = ""
    notes: str = ""

    @property
    def source(self) -> str:
        return next(s for s in SOURCES if getattr(self, s) is not None)

    def files(self) -> tuple[Path, ...]:
        """The files the case reads (none for a synthetic scene)."""
        plane = Path(self.ground_plane) if self.ground_plane not in ("", PLANE_FROM_TRUTH) else None
        return tuple(p for p in (self.video, self.images, self.log, self.truth, plane) if p is not None)

    def missing(self) -> Path | None:
        return next((p for p in self.files() if not p.exists()), None)


@dataclass(frozen=True)
class Corpus:
    path: Path
    name: str
    data_root: Path | None
    cases: tuple[Case, ...]


KNOWN_CASE_KEYS = tuple(f.name for f in fields(Case))
KNOWN_CORPUS_KEYS = ("name", "data_root", "description", "include")
PATH_KEYS = ("video", "images", "log", "truth")
PLANE_FROM_TRUTH = "truth"


def load_corpus(path: str | Path, environ: dict[str, str] | None = None, _seen: tuple[Path, ...] = ()) -> Corpus:
    """Read and check a manifest (and those it includes); every case is checked before anything runs."""
    path = Path(path)
    if path.resolve() in _seen:
        raise SourceError(f"{path} includes itself (through {', '.join(str(p) for p in _seen)})")
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise SourceError(f"corpus manifest {path} does not exist") from None
    except (OSError, UnicodeDecodeError) as err:
        raise SourceError(f"cannot read corpus manifest {path} ({err})") from None
    except tomllib.TOMLDecodeError as err:
        raise SourceError(f"{path} is not valid TOML ({err})") from None
    unknown = sorted(set(data) - {"corpus", "case"})
    if unknown:
        raise SourceError(f"{path}: unknown table(s) {', '.join(unknown)}; a manifest has [corpus] and [[case]] tables")
    head = data.get("corpus", {})
    if not isinstance(head, dict):
        raise SourceError(f"{path}: [corpus] must be a table")
    _refuse_unknown(head, KNOWN_CORPUS_KEYS, f"{path}: [corpus]")
    env = os.environ if environ is None else environ
    root = head.get("data_root")
    if root is not None and not isinstance(root, str):
        raise SourceError(f"{path}: [corpus] data_root must be a path (a string), not {root!r}")
    root = (env.get(DATA_ROOT_ENV) or root) if root else None  # only a manifest that has a data root is moved
    data_root = (path.parent / root).resolve() if root else None
    base = data_root or path.parent.resolve()
    raw = data.get("case", [])
    included = _included(path, head.get("include", []), environ, (*_seen, path.resolve()))
    if not isinstance(raw, list) or not (raw or included):
        raise SourceError(f"{path} lists no [[case]]")
    cases = tuple(c for inc in included for c in inc.cases)
    cases += tuple(parse_case(c, base, f"{path}: case {i + 1}") for i, c in enumerate(raw))
    seen: set[str] = set()
    for c in cases:
        if c.name in seen:
            raise SourceError(f"{path}: two cases are named {c.name!r}; give each case its own name")
        seen.add(c.name)
    return Corpus(path, str(head.get("name", path.stem)), data_root, cases)


def _included(path: Path, include: Any, environ: dict[str, str] | None, seen: tuple[Path, ...]) -> list[Corpus]:
    """The manifests ``[corpus] include`` lists (relative to this one), each with its own data_root."""
    if not isinstance(include, list) or not all(isinstance(p, str) for p in include):
        raise SourceError(f"{path}: [corpus] include must be a list of manifest paths, not {include!r}")
    return [load_corpus(path.parent / p, environ, seen) for p in include]


def _refuse_unknown(table: dict, known: tuple[str, ...], where: str) -> None:
    unknown = sorted(set(table) - set(known))
    if unknown:
        raise SourceError(f"{where}: unknown key(s) {', '.join(unknown)}; known keys: {', '.join(known)}")


def _check(ok: bool, where: str, message: str) -> None:
    if not ok:
        raise SourceError(f"{where}: {message}")


def _int(value: Any) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


def parse_case(table: Any, base: Path, where: str) -> Case:
    """One ``[[case]]`` table as a :class:`Case` (``where`` names the file and the case in errors)."""
    _check(isinstance(table, dict), where, "must be a table")
    name = table.get("name")
    _check(isinstance(name, str) and bool(name.strip()), where, "needs a name (a non-empty string)")
    where = f"{where} ({name})"
    _refuse_unknown(table, KNOWN_CASE_KEYS, where)
    given = [s for s in SOURCES if s in table]
    _check(len(given) == 1, where, f"give exactly one source of {', '.join(SOURCES)}, not {', '.join(given) or 'none'}")
    values: dict[str, Any] = {"name": name}
    for key in PATH_KEYS:
        if key in table:
            _check(isinstance(table[key], str), where, f"{key} must be a path (a string)")
            values[key] = (base / table[key]).resolve()
    values |= _source_options(table, where)
    values |= _truth_options(table, where)
    values |= _start_options(table, where)
    if "ground_plane" in table:
        plane = table["ground_plane"]
        _check(isinstance(plane, str) and bool(plane), where, f"ground_plane must be \"{PLANE_FROM_TRUTH}\" or a path, not {plane!r}")
        _check("video" in table or "images" in table, where, "ground_plane applies to video and images only")
        _check(plane != PLANE_FROM_TRUTH or "truth" in table, where, "ground_plane = \"truth\" needs truth (a file)")
        values["ground_plane"] = plane if plane == PLANE_FROM_TRUTH else str((base / plane).resolve())
    return Case(**values)


def _source_options(table: dict, where: str) -> dict[str, Any]:
    out: dict[str, Any] = {}
    if "seed" in table:
        _check(_int(table["seed"]) and table["seed"] >= 0, where, f"seed must be an integer >= 0, not {table['seed']!r}")
        out["seed"] = table["seed"]
    if "synth" in table:
        options = table.get("synth_options", {})
        _check(isinstance(options, dict), where, "synth_options must be a table of the scene's settings")
        scene_config(table["synth"], table.get("seed", 0), options, where)  # a bad scene or option fails now
        out["synth"] = table["synth"]
        out["synth_options"] = tuple(sorted(options.items()))
    else:
        for key in ("seed", "synth_options"):
            _check(key not in table, where, f"{key} applies to synth cases only")
    if "fps" in table:
        fps = table["fps"]
        _check(isinstance(fps, int | float) and not isinstance(fps, bool) and math.isfinite(fps) and fps > 0, where,
               f"fps must be a positive number, not {fps!r}")
        _check("video" in table or "images" in table, where, "fps applies to video and images only")
        out["fps"] = float(fps)
    _check("images" not in table or "fps" in table, where, "images need fps (the frame rate they were taken at)")
    return out


def _truth_options(table: dict, where: str) -> dict[str, Any]:
    from trackreplay.recorder.sources.groundtruth import FORMATS

    out: dict[str, Any] = {}
    if "truth" in table:
        _check("synth" not in table and "log" not in table, where,
               "truth is recorded with a video or images; a synthetic scene or a log carries its own")
    else:
        _check("video" not in table and "images" not in table, where, "a video or image case needs truth (a file)")
    fmt = table.get("truth_format", "auto")
    _check(fmt in FORMATS, where, f"truth_format {fmt!r} is not one of {', '.join(FORMATS)}")
    out["truth_format"] = fmt
    if "truth_first_frame" in table:
        first = table["truth_first_frame"]
        _check(_int(first) and first >= 0, where, f"truth_first_frame must be a frame number >= 0, not {first!r}")
        out["truth_first_frame"] = first
    target = table.get("target") or _default_target(table, fmt)
    _check(target in TARGETS, where, f"target {target!r} is not one of {', '.join(TARGETS)}")
    out["target"] = target
    if "object" in table:
        _check(_int(table["object"]), where, f"object must be the truth's integer id, not {table['object']!r}")
        out["object"] = table["object"]
    trackers = table.get("trackers", DEFAULT_TRACKERS[target])
    _check(isinstance(trackers, list | tuple) and trackers and all(isinstance(t, str) and registry.known(t) for t in trackers),
           where, f"trackers must be a list of {', '.join(registry.NAMES)} ({registry.aliases_text()}), not {trackers!r}")
    out["trackers"] = tuple(dict.fromkeys(registry.canonical(t) for t in trackers))
    for key, kind in (("label", str), ("notes", str), ("baseline", bool)):
        if key in table:
            _check(isinstance(table[key], kind), where, f"{key} must be a {kind.__name__}, not {table[key]!r}")
            out[key] = table[key]
    return out


def _default_target(table: dict, fmt: str) -> str:
    if "synth" in table:
        return next((t for prefix, t in SYNTH_TARGETS.items() if str(table["synth"]).startswith(prefix)), "box")
    if fmt in POINT_FORMATS:
        return "point"
    if fmt in OBJECT_FORMATS:
        return "objects"
    if fmt == "auto" and "truth" in table and str(table["truth"]).lower().endswith(".csv"):
        return "point"  # frame,visible,x,y labels, TrackNet's Label.csv, frame,x,y references
    return "box"


def _start_options(table: dict, where: str) -> dict[str, Any]:
    out: dict[str, Any] = {}
    if "start" in table:
        start = table["start"]
        frames = [start] if _int(start) else start
        _check(isinstance(frames, list) and frames and all(_int(f) and f >= 0 for f in frames), where,
               f"start must be a frame number >= 0 or a list of them (re-marks), not {start!r}")
        out["start"] = tuple(sorted(set(frames)))
    if "mark_size" in table:
        size = table["mark_size"]
        _check(isinstance(size, int | float) and not isinstance(size, bool) and math.isfinite(size) and size >= 1, where,
               f"mark_size must be a number of pixels >= 1, not {size!r}")
        out["mark_size"] = float(size)
    if "marks" in table:
        _check(table["marks"] in MARK_MODES, where, f"marks must be one of {', '.join(MARK_MODES)}, not {table['marks']!r}")
        _check(table["marks"] == "truth" or ("synth" in table or "log" in table), where,
               "marks = \"log\" needs a log or a synthetic scene (they carry marks); a recording has none")
        out["marks"] = table["marks"]
    return out
