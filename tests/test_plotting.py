import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from skatetrace import pattern, trace_figure, verify  # noqa: E402
from skatetrace import plotting  # noqa: E402


def test_plots_have_content(tmp_path):
    tr = trace_figure(pattern("circle"))
    rep = verify(tr)
    for fn, ylabel in ((plotting.plot_figure, "y"), (plotting.plot_controls, "mass position (body frame)"),
                       (plotting.plot_speed, "xi2"), (plotting.plot_mass_path, "b (left of the blade)"),
                       (plotting.plot_energies, "kinetic energy")):
        fig, ax = plt.subplots()
        artists = fn(tr, rep, ax=ax)
        assert len(artists) >= 2 and len(ax.lines) >= 2
        assert ax.get_ylabel() == ylabel
        plt.close(fig)
    written = plotting.save_all(tr, rep, tmp_path)
    assert len(written) == 5 and all(p.stat().st_size > 5000 for p in written)
