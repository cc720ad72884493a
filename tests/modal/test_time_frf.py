"""A time file → its FRFs with the fit's time options (modal.time_frf), shared by modal fit, modal frf and batch."""
import numpy as np

from modal.estimate import EstimatedFRF
from modal.fitting import FitOptions, fit_path
from modal.time_frf import frf_from_time, wants_time
from support.timedata import DigitalModes

FS = 512.0


def _time_csv(path, seed=0, n=2**14):
    rng = np.random.default_rng(seed)
    force = rng.standard_normal(n)
    plant = DigitalModes(np.array([40.0]), np.array([0.03]), np.array([[1.0]]), FS)
    displacement = plant.respond(force)[0]
    table = np.column_stack([np.arange(n) / FS, force, displacement])
    np.savetxt(path, table, delimiter=",", header="time [s],force [N],tip [m]", comments="")
    return path


def test_a_time_file_is_read_without_printing_and_the_choice_of_excitation_is_reported(tmp_path, capsys):
    path = _time_csv(tmp_path / "record.csv")
    options = FitOptions()
    assert wants_time(options.namespace(), path)
    notes = []
    estimate, record, inputs, outputs = frf_from_time(path, options.namespace(), notes.append)
    assert isinstance(estimate, EstimatedFRF) and inputs == [0] and outputs == [1]
    assert notes == [f"{record.source}: excitation channel 1 (force)"]
    # the library writes nothing itself; the command line prints the note it is given
    fitted = fit_path(path, FitOptions(method="nls"))
    assert fitted.time_data is not None and len(fitted.results) == 1
    assert capsys.readouterr() == ("", "")


def test_the_frf_unit_is_what_the_channels_were_recorded_in(tmp_path):
    """A force in N over a response of known quantity gives the kind's unit; an excitation recorded in volts (taken as
    the force, with a warning) gives m/.../V, and a response of unknown quantity keeps its own unit: never m/N by
    default for what was not a force in N."""
    import pytest

    from modal.errors import ModalWarning

    path = _time_csv(tmp_path / "record.csv")
    text = path.read_text()
    assert frf_from_time(path, FitOptions().namespace())[0].units == "m/N"
    (tmp_path / "volts.csv").write_text(text.replace("force [N]", "drive [V]"))
    with pytest.warns(ModalWarning, match="does not say it measured force"):
        estimate = frf_from_time(tmp_path / "volts.csv", FitOptions(excitation="1").namespace())[0]
    assert estimate.units == "m/V"
    (tmp_path / "unknown.csv").write_text(text.replace("tip [m]", "tip [counts]"))
    estimate = frf_from_time(tmp_path / "unknown.csv", FitOptions(kind="receptance").namespace())[0]
    assert estimate.units == "counts/N"
