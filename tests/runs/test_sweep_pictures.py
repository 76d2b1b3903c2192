"""The sweep's picture, read from its figure: units on both axes, numeric parameters spaced by
their values, and a title that fits and says what was run (the revolutions run, not the
description's)."""
import pytest

from sewfmu.scenarios.format.loader import load
from sewfmu.scenarios.runs.sweep import declared_unit, sweep_figure, sweep_title

OMEGAS = [100.0, 150.0, 400.0]          # unevenly spaced: the axis keeps their distances
ROWS = [{"index": i, "shaft.omega0": w, "punch.F30": f, "status": "ok",
         "F2_weld_mean": 20.0 + w / 100 + f, "contact_onset_deg": 200.0 + f}
        for i, (w, f) in enumerate((w, f) for w in OMEGAS for f in (5.0, 10.0))]
FIGURES = {"F2_weld_mean": "N", "contact_onset_deg": "deg"}


@pytest.fixture
def scenario():
    sc = load("punch_drive")          # its description says 10 revolutions
    sc.set_value("experiment.revolutions", 3)
    return sc


@pytest.fixture
def figure(scenario):
    import matplotlib.pyplot as plt

    swept = ["shaft.omega0", "punch.F30"]
    fig = sweep_figure(ROWS, swept, FIGURES, {p: declared_unit(scenario, p) for p in swept},
                       sweep_title(scenario, ROWS, swept))
    yield fig
    plt.close(fig)


def test_both_axes_carry_their_units(figure):
    axes = figure.axes
    assert axes[2].get_xlabel() == "shaft.omega0 [rad/s]"
    assert axes[3].get_xlabel() == "punch.F30 [N]"
    assert axes[0].get_ylabel() == "F2_weld_mean [N]"
    assert axes[2].get_ylabel() == "contact_onset_deg [deg]"


def test_a_numeric_parameter_is_spaced_by_its_values(figure):
    for line in figure.axes[0].get_lines():
        assert list(line.get_xdata()) == OMEGAS
    assert figure.axes[0].get_xlim()[0] < 100.0 and figure.axes[0].get_xlim()[1] > 400.0
    assert [line.get_label() for line in figure.axes[0].get_lines()] == ["F30=5 N", "F30=10 N"]


def test_the_title_says_what_was_run_and_fits(figure):
    title = figure._suptitle.get_text().replace("\n", " ")
    assert "3 revolutions of shaft" in title and "10 revolutions" not in title
    assert "step 0.25 ms" in title and "jacobi" in title and "6 points" in title
    renderer = figure.canvas.get_renderer()
    figure.draw(renderer)
    box, page = figure._suptitle.get_window_extent(renderer), figure.bbox
    assert page.x0 <= box.x0 and box.x1 <= page.x1 and box.y1 <= page.y1


def test_a_parameter_that_is_no_number_gets_one_tick_per_value(scenario):
    import matplotlib.pyplot as plt

    rows = [{"experiment.master": m, "status": "ok", "F2_weld_mean": v}
            for m, v in (("jacobi", 24.0), ("gauss-seidel", 24.2))]
    fig = sweep_figure(rows, ["experiment.master"], {"F2_weld_mean": "N"}, {}, "masters")
    ax = fig.axes[0]
    assert [t.get_text() for t in ax.get_xticklabels()] == ["jacobi", "gauss-seidel"]
    assert list(ax.get_lines()[0].get_xdata()) == [0, 1] and ax.get_xlabel() == \
        "experiment.master"
    plt.close(fig)
