"""uavsim.BeamEnv: the run one alignment window at a time, for learned beam
tracking (the paper's Sec. VI-C application), with Gymnasium's conventions
(reset(seed) -> (obs, info), step(action) -> (obs, reward, terminated,
truncated, info)) and no dependency on it."""
import json
import shutil
import tempfile

from . import _uavsim
from ._method import split_methods
from ._scenario import Scenario


class BeamEnv:
    """One step is one alignment window (0.2 s by default).

    observation (dict)  k, t_s (the window's end), base_station (its array's
        position), estimates {method: [x, y, z]} (each method's estimate at
        this window, as scored), arrivals: what reached the edge on time in
        the window, one entry per message (node [str], modality [int: 0
        camera, 1 LiDAR, 2 radar], t_capture_s, latent [N, z] (float32, z 0
        without a model), anchor_kind [0 nothing found, 1 a point, 2 a ray],
        anchor_origin [N, 3] and anchor_direction [N, 3]: the node's
        detection as its geometric anchor, world ENU)
    action  the beam's direction from the base station's array (3 numbers,
        world ENU, any length), or None: the beam of the method `steer_by`
    reward  the window's achievable rate log2(1 + SNR gamma) (bit/s/Hz) at
        `snr_db`, gamma the beam's gain on the window's channel; a beam
        that copies a method's gives that method's rate, whose mean over the
        run is its rate_snr.csv value at snr_db
    info    truth [x, y, z] at the window's end, k, t_s, rates {beam: this
        window's rate of each steering method's beam and of "perfect"}
    terminated when the run is over (the last window was scored); the
    observation is then the last one. Deterministic per seed.
    """

    def __init__(self, scenario, snr_db=10.0, steer_by="ekf", methods=None, duration=None,
                 quiet=True):
        self.scenario = Scenario(scenario)
        self.snr_db, self.steer_by, self.quiet = float(snr_db), steer_by, quiet
        self._entries, self._hosted = split_methods(methods)
        self._methods = methods
        self._duration = duration
        self._stepper = None
        self._tmp = None

    def reset(self, seed=None, options=None):
        self.close()
        extra = []
        if self._methods is not None:
            extra.append("/pipeline/methods=" + json.dumps(self._entries))
        if seed is not None:
            extra.append("/seed=%d" % seed)
        if self._duration is not None:
            extra.append("/duration_s=" + json.dumps(self._duration))
        self._tmp = tempfile.mkdtemp(prefix="uavsim-env-")
        path, document, overrides = self.scenario._args(extra)
        self._stepper = _uavsim.Stepper(path, document, overrides, self._tmp + "/run",
                                        self.snr_db, self.steer_by, self.quiet, self._hosted)
        obs = self._stepper.reset()
        return obs, self._stepper.info

    def step(self, action):
        if self._stepper is None:
            raise RuntimeError("step() before reset()")
        obs, reward, terminated, info = self._stepper.step(action)
        return obs, reward, terminated, False, info

    def close(self):
        if self._stepper is not None:
            self._stepper.close()
            self._stepper = None
        if self._tmp:
            shutil.rmtree(self._tmp, ignore_errors=True)
            self._tmp = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def __del__(self):
        try:
            self.close()
        except Exception:
            pass
