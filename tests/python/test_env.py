"""uavsim.BeamEnv: a window per step; rewards against rate_snr.csv."""
import numpy as np
import pytest
import uavsim
from conftest import DEFAULT

SECONDS = 3
SNR_DB = 10.0


def episode(policy, seed=2, steer_by="ekf"):
    env = uavsim.BeamEnv(DEFAULT, snr_db=SNR_DB, steer_by=steer_by, duration=SECONDS)
    obs, info = env.reset(seed=seed)
    rewards, infos, observations = [], [info], [obs]
    terminated = False
    while not terminated:
        obs, reward, terminated, truncated, info = env.step(policy(obs))
        assert truncated is False
        rewards.append(reward)
        infos.append(info)
        observations.append(obs)
    env.close()
    return np.array(rewards), infos, observations


def rate_at(run, beam):
    table = run.rate_snr[beam]
    return float(table["rate_bps_hz"][np.isclose(table["snr_db"], SNR_DB)][0])


def test_rewards_of_a_copied_beam_average_to_rate_snr():
    run = uavsim.run(DEFAULT, seed=2, duration=SECONDS, quiet=True)
    windows = round(SECONDS / 0.2)
    # None: the beam of steer_by; a direction at the method's estimate: the same beam.
    by_none, infos, _ = episode(lambda obs: None)
    assert len(by_none) == windows
    assert abs(by_none.mean() - rate_at(run, "ekf")) < 1e-6

    def copy_uavloc(obs):
        est = obs["estimates"].get("uavloc")
        return None if est is None else est - obs["base_station"]

    copied, infos, _ = episode(copy_uavloc, steer_by="uavloc")
    assert abs(copied.mean() - rate_at(run, "uavloc")) < 1e-6
    # Each step's reward is the window's rate of that beam in info.
    assert np.allclose(copied, [i["rates"]["uavloc"] for i in infos[:-1]], rtol=1e-12, atol=0)


def test_the_perfect_beam_bounds_a_naive_policy_and_steps_are_deterministic():
    def naive(obs):  # towards the centroid of the nodes' point detections
        a = obs["arrivals"]
        points = a["anchor_origin"][a["anchor_kind"] == 1]
        return None if len(points) == 0 else points.mean(axis=0) - obs["base_station"]

    r1, infos, observations = episode(naive)
    r2, _, _ = episode(naive)
    assert np.array_equal(r1, r2)
    perfect = np.array([i["rates"]["perfect"] for i in infos[:-1]])
    assert np.all(r1 <= perfect + 1e-9)
    assert observations[0]["k"] == 1 and observations[1]["k"] == 2
    first = observations[0]["arrivals"]
    assert first["latent"].shape[1] in (0, 16) and first["anchor_origin"].shape[1] == 3
    assert np.allclose(infos[0]["truth"].shape, (3,))


def test_bad_actions_are_refused():
    env = uavsim.BeamEnv(DEFAULT, duration=1)
    env.reset(seed=1)
    with pytest.raises(ValueError):
        env.step([0.0, 0.0, 0.0])
    with pytest.raises(ValueError):
        env.step([1.0, 2.0])
    env.close()
