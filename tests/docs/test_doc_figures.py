"""The accuracy figures that README.md and docs/ quote hold for the code as it is.

docs/tools/doc_figures.py computes them and writes them between `<!-- figures: NAME -->` markers; here
they are parsed back and recomputed: the README's (cheap: one tight monolithic solve and a dozen
short runs) in the fast loop, every block of every page in a slow test. A figure holds within 2 %
or one unit of its last printed digit, whichever is larger; a "within X" holds if the computed
figure is not above X. When one fails, `.venv/bin/python docs/tools/doc_figures.py` rewrites the
figures (and says which promise it had to loosen)."""
import importlib.util
import re
import sys

import pytest

from tests.paths import REPO


def _doc_figures():
    """bench/ is scripts, not a package: the module loaded from its file (registered first, as
    its dataclasses look their module up)."""
    spec = importlib.util.spec_from_file_location("doc_figures", REPO / "docs" / "tools" / "doc_figures.py")
    module = sys.modules.setdefault("doc_figures", importlib.util.module_from_spec(spec))
    spec.loader.exec_module(module)
    return module


doc_figures = _doc_figures()


@pytest.fixture(scope="module")
def figures(fmu_paths):
    """One set of computed figures for the module: the slow test reuses the README's runs."""
    return doc_figures.Figures(fmu_paths)


def test_numbers_are_printed_read_and_compared_as_the_docs_need():
    fmt, parse, last, round_up, close = (doc_figures.fmt, doc_figures.parse_number,
                                         doc_figures.last_digit, doc_figures.round_up,
                                         doc_figures.close)
    assert [fmt(x, s) for x, s in ((8.04e-5, "g2"), (-0.00655, "s2"), (3.46e-7, "e2"),
                                   (1.79e-8, "u2"), (1.4749, "f3"), (234.0, "d"))] == \
        ["8e-05", "−0.0066", "3.5e-7", "1.8·10⁻⁸", "1.475", "234"]
    assert parse("−0.0066") == -0.0066 and parse("1.8·10⁻⁸") == pytest.approx(1.8e-8)
    assert last("0.0012") == pytest.approx(1e-4) and last("9.6e-05") == pytest.approx(1e-6)
    assert last("1.8·10⁻⁸") == pytest.approx(1e-9) and last("17") == 1.0
    # a bound rounds up at its printed precision, so that it holds
    assert round_up(0.0303, "g2") == "0.031" and round_up(9.6e-5, "g1") == "0.0001"
    assert round_up(0.044, "g1") == "0.05" and round_up(0.0026, "g2") == "0.0026"
    # 2 % or one unit of the last printed digit, whichever is larger
    assert close("0.033", 0.0335) and not close("0.033", 0.044)
    assert close("17", 17.9) and not close("17", 18.5) and close("1.48", 1.4749)
    assert close("diverged", float("nan")) and not close("0.1", float("nan"))


def test_every_block_is_in_its_page_in_the_scripts_layout():
    """Every block the script writes is in its page, each parses with its template (a block
    edited by hand into another shape fails here, before anything is computed)."""
    for doc, blocks in doc_figures.BLOCKS.items():
        found = doc_figures.blocks_of((REPO / doc).read_text(encoding="utf-8"))
        for name in doc_figures.WRITTEN_ELSEWHERE.get(doc, ()):   # bench/estimate_bounds.py's
            found.pop(name)
        assert set(found) == set(blocks), (doc, set(found) ^ set(blocks))
        for name, template in blocks.items():
            assert doc_figures.parse(template, found[name][1]) is not None, (doc, name)


def test_every_within_in_the_docs_is_checked():
    """A "within <number>" in README.md or docs/ lies in a block (computed and checked here) or
    is one of the few the script names as checked elsewhere, with the reason."""
    elsewhere = sorted(doc_figures.WITHIN_ELSEWHERE, key=len, reverse=True)  # longest first
    used = set()
    for doc in [REPO / "README.md", *sorted((REPO / "docs").glob("*.md"))]:
        # outside the blocks, the line breaks of the prose as spaces
        text = " ".join(doc_figures.MARKER.sub("", doc.read_text(encoding="utf-8")).split())
        for phrase in elsewhere:
            used |= {phrase} if phrase in text else set()
            text = text.replace(phrase, "")
        unchecked = re.findall(r"within [~≈]?[-+]?\d[^ ]*(?: [^ ]+){0,3}", text)
        assert not unchecked, (doc.name, unchecked)
    assert used == set(elsewhere), ("named as checked elsewhere, found nowhere", set(elsewhere) - used)


@pytest.mark.slow
def test_the_figures_of_the_readme_hold(figures):
    failures = doc_figures.check(figures, files=["README.md"])
    assert not failures, "\n".join(failures)


@pytest.mark.slow
def test_every_figure_in_the_docs_holds(figures):
    failures = doc_figures.check(figures)
    assert not failures, "\n".join(failures)
