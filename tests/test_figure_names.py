"""Names a user chose (configuration, bike file, run folder) enter figure titles as written: a
``$...$`` in one was parsed as mathtext and gave a traceback after the whole run (issue 37)."""
import pytest

from mtbmj import cli

NAMES = ["a$\\frac{b$", "cost$5", "x$^{$y", "$$", "\\$ok$"]


@pytest.mark.parametrize("name", NAMES)
def test_drop_with_a_mathtext_name_draws_it_as_written(tmp_path, monkeypatch, capsys, name):
    monkeypatch.chdir(tmp_path)
    (tmp_path / f"{name}.toml").write_text('base = "S1"\n')
    assert cli.main(["drop", f"{name}.toml", "--duration", "0.2", "--out", "out"]) == 0
    assert "Traceback" not in capsys.readouterr().err
    assert (tmp_path / "out" / "quicklook.png").stat().st_size > 10000


def test_every_text_of_a_figure_is_plain():
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    from mtbmj.readout.quicklook import plain_text, png

    fig, ax = plt.subplots()
    ax.plot([0, 1], [0, 1], label="x$^{$")
    ax.legend()
    ax.set_title("a$\\frac{b$")
    fig.suptitle("$\\sqrt{")
    try:
        assert png(fig)[:4] == b"\x89PNG"
        assert all(not t.get_parse_math() for t in plain_text(fig).findobj(matplotlib.text.Text))
    finally:
        plt.close(fig)


def test_bike_with_a_mathtext_file_name(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "my$\\sqrt{bike$.toml").write_text('base = "sst"\n')
    assert cli.main(["bike", "my$\\sqrt{bike$.toml", "flat", "--speed", "4", "--duration", "0.3", "--out", "out"]) == 0
    assert "Traceback" not in capsys.readouterr().err
    assert (tmp_path / "out" / "quicklook.png").stat().st_size > 10000
