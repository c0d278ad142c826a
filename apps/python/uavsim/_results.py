"""A run directory's tables as NumPy structured arrays (docs/run-directory.md)."""
import csv
import json
import os

import numpy as np


def read_csv(path):
    """A CSV table as a structured array: a column of numbers as float64
    (int64 when every value is an integer), any other column as str."""
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    header, body = rows[0], rows[1:]
    columns = []
    for i, name in enumerate(header):
        values = [r[i] for r in body]
        columns.append(_column(values))
    if not body:
        return np.zeros(0, dtype=[(n, "f8") for n in header])
    return np.rec.fromarrays(columns, names=header).view(np.ndarray)


def _column(values):
    try:
        ints = [int(v) for v in values]
        return np.array(ints, dtype=np.int64)
    except ValueError:
        pass
    try:
        return np.array([float(v) for v in values], dtype=np.float64)
    except ValueError:
        return np.array(values, dtype=str)


def by_method(table, column="method"):
    """{method: rows of that method without the method column}, in first-seen order."""
    names = [n for n in table.dtype.names if n != column]
    out = {}
    for m in dict.fromkeys(table[column].tolist()):
        rows = table[table[column] == m]
        out[m] = np.rec.fromarrays([rows[n] for n in names], names=names).view(np.ndarray)
    return out


class Run:
    """One run's results.

    metrics    metrics.json as a dict (rmse_m, rmse_common_m, packets, data rates, ...)
    rmse       {method: RMSE in metres or None}, as `uavsim run` prints them
    truth      truth.csv: t_s, x_m, y_m, z_m, vx_mps, vy_mps, vz_mps
    estimates  {method: t_s, x_m, y_m, z_m} from estimates.csv (and track, with
               several targets or a multi-target method: a track's label, 0
               for a method's single estimate)
    packets    packets.csv: every uplink message (t_capture_s, node, modality, ...)
    rate_snr   {beam: (snr_db, rate_bps_hz)} from rate_snr.csv, as a structured array each
    dir        the run directory (None when the run was not kept)
    """

    def __init__(self, folder, keep):
        self.dir = folder if keep else None
        with open(os.path.join(folder, "metrics.json")) as f:
            self.metrics = json.load(f)
        with open(os.path.join(folder, "manifest.json")) as f:
            self.manifest = json.load(f)
        self.rmse = dict(self.metrics["rmse_m"])
        self.truth = read_csv(os.path.join(folder, "truth.csv"))
        estimates = read_csv(os.path.join(folder, "estimates.csv"))
        self.estimates = by_method(estimates)
        columns = [n for n in estimates.dtype.names if n != "method"]
        for m in self.rmse:
            self.estimates.setdefault(m, np.zeros(0, dtype=[(n, "f8") for n in columns]))
        self.packets = read_csv(os.path.join(folder, "packets.csv"))
        self.rate_snr = by_method(read_csv(os.path.join(folder, "rate_snr.csv")), column="beam")

    def __repr__(self):
        rmse = ", ".join("%s %s" % (m, "n/a" if v is None else "%.3f m" % v) for m, v in self.rmse.items())
        return "Run(%s; RMSE %s)" % (self.dir or "not kept", rmse)
