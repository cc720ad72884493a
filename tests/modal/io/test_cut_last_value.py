"""Text tables cut inside their last number (``refuse_cut_last_value``): the time CSV and the FRF CSV readers
refuse a file that ends, without a line break, inside a value shorter than every other of its column (it would
parse to a wrong last sample); whole files, and files merely lacking the final line break, read as before."""
from __future__ import annotations

import numpy as np

from modal.io import read_frf
from modal.io.timedata import read_time
from support.refusals import assert_refused

FS = 1000.0


def _time_csv(tmp_path, n=40):
    """A time CSV as a logger writes it, fixed-width %.6e fields, and its text."""
    t = np.arange(n) / FS
    rows = [f"{tk:.6e},{np.sin(40 * tk):.6e},{np.cos(90 * tk) * 1e-3:.6e}" for tk in t]
    return "time,force [N],a [m/s^2]\n" + "\n".join(rows)


def test_time_csv_cut_inside_its_last_number_is_refused(tmp_path):
    text = _time_csv(tmp_path)
    last = text.rsplit(",", 1)[1]
    path = tmp_path / "cut.csv"
    # cut 4 characters before the end: '-9.364566e-04' becomes '-9.364566e' (not a number) or, one more
    # character gone, '-9.364566' (a number 10^4 times too large, read silently before)
    for keep in (len(text) - 3, len(text) - 4):
        path.write_text(text[:keep])
        assert_refused(path, read_time, "line 41, column 'a [m/s^2]'", repr(text[:keep].rsplit(",", 1)[1]),
                 "ends inside it", "delete line 41")
    assert len(last) == 13


def test_time_csv_whole_without_a_final_line_break_reads_every_sample(tmp_path):
    text = _time_csv(tmp_path)
    path = tmp_path / "whole.csv"
    path.write_text(text)  # a whole last row: no line break, but as long as the others
    record = read_time(path)
    assert record.n_samples == 40
    assert record.signals[-1, -1] == float(text.rsplit(",", 1)[1])
    path.write_text(text + "\n")
    assert read_time(path).n_samples == 40


def _frf_csv(n=41):
    freq = 2.0 + 0.25 * np.arange(n)
    h = 1.0 / (100.0 - freq ** 2 + 0.5j * freq)
    rows = [f"{f:.6e},{v.real:.6e},{v.imag:.6e}" for f, v in zip(freq, h)]
    return "# kind: receptance\nfrequency_hz,re,im\n" + "\n".join(rows)


def test_frf_csv_cut_inside_its_last_number_is_refused(tmp_path):
    text = _frf_csv()
    path = tmp_path / "cut.csv"
    path.write_text(text[:-4])
    assert_refused(path, read_frf, "line 43, column 'im'", "ends inside it")
    path.write_text(text)
    assert read_frf(path).n_freq == 41
