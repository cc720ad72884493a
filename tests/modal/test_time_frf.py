"""A time file → its FRFs with the fit's time options (modal.time_frf), shared by modal fit, modal frf and batch."""
import numpy as np

from modal.estimate import EstimatedFRF
from modal.fitting import FitOptions, fit_path
from modal.time_frf import frf_from_time, wants_time
from support.timedata import DigitalModes

FS = 512.0


def _time_csv(path, seed=0, n=2**14, names=("force", "tip")):
    rng = np.random.default_rng(seed)
    force = rng.standard_normal(n)
    plant = DigitalModes(np.array([40.0]), np.array([0.03]), np.array([[1.0]]), FS)
    displacement = plant.respond(force)[0]
    table = np.column_stack([np.arange(n) / FS, force, displacement])
    np.savetxt(path, table, delimiter=",", header=f"time [s],{names[0]} [N],{names[1]} [m]", comments="")
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

def test_k_c_m_of_a_time_record_only_where_its_point_ids_or_the_user_say_where_the_response_was(tmp_path):
    import pytest

    # column names that are not point ids ("force", "tip") do not say where the hammer and the sensor stood:
    # not a transfer FRF (no not_driving_point), not a driving point either
    unknown = fit_path(_time_csv(tmp_path / "names.csv"), FitOptions(method="nls")).results[0].modes[0]
    assert unknown.flags == ("driving_point_unknown",) and np.isnan(unknown.mass_kg)
    # declared by channel number (counted from 1) or by the response's name: the plant's 1 kg comes back
    # within 3 standard errors (the leakage bias of the Hann-windowed H1 estimate is far below its scatter)
    for declared in (("1",), ("tip",)):
        mode = fit_path(tmp_path / "names.csv", FitOptions(method="nls", driving_point=declared)).results[0].modes[0]
        assert mode.flags == () and mode.mass_kg == pytest.approx(1.0, abs=3 * mode.std.mass_kg)
    # point ids in the names: force and response at 3+Z make a driving point, 3+Z -> 4+Z a transfer FRF
    same = fit_path(_time_csv(tmp_path / "same.csv", names=("3+Z", "3+Z")), FitOptions(method="nls"))
    assert same.results[0].modes[0].flags == () and np.isfinite(same.results[0].modes[0].mass_kg)
    other = fit_path(_time_csv(tmp_path / "other.csv", names=("3+Z", "4+Z")), FitOptions(method="nls"))
    assert other.results[0].modes[0].flags == ("not_driving_point",)


def test_impact_options_without_impact_are_refused_naming_the_file_and_the_options(tmp_path):
    import pytest

    from modal.errors import ParameterError

    path = _time_csv(tmp_path / "record.csv")
    for options, given in ((FitOptions(window="force"), "--window 'force'"),
                           (FitOptions(window="exponential", exponential_decay_s=0.5), "--window 'exponential'"),
                           (FitOptions(exponential_decay_s=0.5), "--exponential-decay-s")):
        with pytest.raises(ParameterError) as caught:
            frf_from_time(path, options.namespace(), None)
        message = str(caught.value)
        assert message.startswith(f"{path}: {given} is for impact records") and "--impact as well" in message, message
