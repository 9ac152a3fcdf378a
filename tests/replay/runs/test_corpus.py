"""The corpus manifest of `trackreplay evaluate`: keys checked, paths resolved, defaults per target."""

from __future__ import annotations

from pathlib import Path

import pytest

from trackreplay.replay.runs.corpus import DATA_ROOT_ENV, KNOWN_CASE_KEYS, load_corpus
from trackreplay.schemas.errors import SourceError

CORPORA = Path(__file__).resolve().parents[3] / "benchmarks" / "corpora"


def _manifest(tmp_path: Path, text: str, name: str = "suite.toml") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


def test_paths_are_relative_to_the_manifest_and_defaults_follow_the_target(tmp_path: Path) -> None:
    path = _manifest(tmp_path, """
[[case]]
name = "rally"
video = "clips/rally.mp4"
truth = "clips/labels.csv"
truth_format = "points"
start = [40, 12]

[[case]]
name = "walker"
images = "seq/img"
fps = 30
truth = "seq/groundtruth_rect.txt"

[[case]]
name = "plaza"
video = "plaza.avi"
truth = "gt.txt"
truth_format = "mot"
""")
    rally, walker, plaza = load_corpus(path, environ={}).cases
    assert rally.video == tmp_path / "clips" / "rally.mp4" and rally.truth == tmp_path / "clips" / "labels.csv"
    assert (rally.target, rally.trackers, rally.start, rally.mark_size) == ("point", ("golf",), (12, 40), 12.0)
    assert (walker.target, walker.trackers, walker.fps, walker.start) == ("box", ("colorpf", "flow"), 30.0, ())
    assert (plaza.target, plaza.trackers) == ("objects", ("groups",))
    assert rally.missing() == tmp_path / "clips" / "rally.mp4"


def test_an_unknown_key_is_refused_naming_the_file_the_case_and_the_known_keys(tmp_path: Path) -> None:
    path = _manifest(tmp_path, '[[case]]\nname = "a"\nsynth = "flow-sim1"\nstrat = 3\n')
    with pytest.raises(SourceError) as err:
        load_corpus(path, environ={})
    text = str(err.value)
    assert str(path) in text and "case 1 (a)" in text and "strat" in text
    assert all(k in text for k in KNOWN_CASE_KEYS)
    assert "\n" not in text


@pytest.mark.parametrize("body, words", [
    ('name = "a"\nvideo = "v.mp4"\nimages = "d"\nfps = 3\ntruth = "t.txt"', "exactly one source"),
    ('name = "a"\nimages = "d"\ntruth = "t.txt"', "need fps"),
    ('name = "a"\nvideo = "v.mp4"', "needs truth"),
    ('name = "a"\nsynth = "flow-sim1"\ntruth = "t.txt"', "carries its own"),
    ('name = "a"\nsynth = "flow-sim9"', "not a scene"),
    ('name = "a"\nsynth = "flow-sim1"\nsynth_options = { frams = 3 }', "frames"),
    ('name = "a"\nsynth = "flow-sim1"\ntrackers = ["kcf"]', "trackers must be"),
    ('name = "a"\nsynth = "flow-sim1"\nstart = [-1]', "start must be"),
    ('name = "a"\nsynth = "flow-sim1"\ntruth_format = "xml"', "truth_format"),
    ('name = "a"\nvideo = "v.mp4"\ntruth = "t.txt"\nmarks = "log"', "needs a log"),
])
def test_a_bad_case_is_one_sentence(tmp_path: Path, body: str, words: str) -> None:
    with pytest.raises(SourceError, match=words):
        load_corpus(_manifest(tmp_path, f"[[case]]\n{body}\n"), environ={})


def test_two_cases_with_one_name_are_refused(tmp_path: Path) -> None:
    text = '[[case]]\nname = "a"\nsynth = "flow-sim1"\n' * 2
    with pytest.raises(SourceError, match="two cases are named 'a'"):
        load_corpus(_manifest(tmp_path, text), environ={})


def test_data_root_is_relative_to_the_manifest_and_the_environment_overrides_it(tmp_path: Path) -> None:
    path = _manifest(tmp_path, '[corpus]\ndata_root = "data"\n[[case]]\nname = "a"\nvideo = "v.mp4"\ntruth = "t.txt"\n')
    assert load_corpus(path, environ={}).cases[0].video == tmp_path / "data" / "v.mp4"
    elsewhere = tmp_path / "elsewhere"
    assert load_corpus(path, environ={DATA_ROOT_ENV: str(elsewhere)}).cases[0].video == elsewhere / "v.mp4"
    local = _manifest(tmp_path, '[[case]]\nname = "a"\nvideo = "v.mp4"\ntruth = "t.txt"\n', "local.toml")
    assert load_corpus(local, environ={DATA_ROOT_ENV: str(elsewhere)}).cases[0].video == tmp_path / "v.mp4"


def test_include_joins_manifests_with_their_own_roots(tmp_path: Path) -> None:
    (tmp_path / "sub").mkdir()
    _manifest(tmp_path / "sub", '[corpus]\ndata_root = "d"\n[[case]]\nname = "a"\nvideo = "v.mp4"\ntruth = "t.txt"\n', "a.toml")
    top = _manifest(tmp_path, '[corpus]\ninclude = ["sub/a.toml"]\n[[case]]\nname = "b"\nsynth = "flow-sim1"\n')
    a, b = load_corpus(top, environ={}).cases
    assert a.video == tmp_path / "sub" / "d" / "v.mp4" and b.synth == "flow-sim1"
    loop = _manifest(tmp_path, '[corpus]\ninclude = ["loop.toml"]\n', "loop.toml")
    with pytest.raises(SourceError, match="includes itself"):
        load_corpus(loop, environ={})


def test_the_repository_corpora_load() -> None:
    """Every manifest in benchmarks/corpora is valid whether or not the real data is here."""
    names = set()
    for path in sorted(CORPORA.glob("*.toml")):
        corpus = load_corpus(path)
        assert corpus.cases
        if not path.name.startswith("docs-"):  # a docs page's own cases (its marks), not the developer corpus
            names |= {c.name for c in corpus.cases}
    developer = {c.name for c in load_corpus(CORPORA / "developer.toml").cases}
    assert developer == names  # the developer corpus is every case of the others
    targets = {c.target for c in load_corpus(CORPORA / "developer.toml").cases}
    assert targets == {"box", "point", "objects"}
