"""The VectorEnv contract, as Gymnasium's own tests (its tests/vector/) check it, for the native
vector envs beside SyncVectorEnv and AsyncVectorEnv of the same single envs: the same games for
the same seeds and actions, the three autoreset modes, partial resets and their errors, action
checks, seeding, and get_attr / set_attr / call."""

import re

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils import seeding
from gymnasium.vector import AsyncVectorEnv, AutoresetMode, SyncVectorEnv, VectorEnv
from packaging.version import Version

import pinball_env  # noqa: F401  (registers the envs)
from pinball_env.envs import PinballVectorEnv

# Short games: one ball, three frames a step, and a time limit, so that episodes end (both ways)
# within a few hundred steps. Procgen plays two layouts (tables are cached for the session).
ENVS = {
    "Pinball-v0": {"balls": 1, "frame_skip": 3, "max_episode_steps": 60},
    # (a ball waits on the plunger: longer steps, so that random play drains one in time)
    "Pinball-v1": {"balls": 1, "frame_skip": 15, "max_episode_steps": 60},
    "PinballProcgen-v0": {"balls": 1, "frame_skip": 3, "max_episode_steps": 60,
                          "num_layouts": 2, "rays": 4},
}  # fmt: skip
KINDS = ("native", "sync", "async")
INFO_KEYS = ("ball_position", "ball_velocity", "score", "balls_left", "points", "drained", "frames")
# AsyncVectorEnv logs a worker's error (then raises it) as warnings.
ASYNC_ERRORS_LOGGED = pytest.mark.filterwarnings("ignore:.*ERROR:UserWarning")


def make(kind: str, env_id: str, num_envs: int = 3, mode=AutoresetMode.NEXT_STEP, **kwargs):
    """The native vector env, or Gymnasium's sync or async one of the single envs."""
    kwargs = {**ENVS[env_id], **kwargs}
    if kind == "native":
        return gym.make_vec(env_id, num_envs, vectorization_mode="vector_entry_point",
                            autoreset_mode=mode, **kwargs)  # fmt: skip
    return gym.make_vec(env_id, num_envs, vectorization_mode=kind,
                        vector_kwargs={"autoreset_mode": mode}, disable_env_checker=True,
                        **kwargs)  # fmt: skip


@pytest.fixture(params=list(ENVS))
def env_id(request) -> str:
    return request.param


def assert_infos_equal(native: dict, other: dict, envs: np.ndarray) -> None:
    """The single env's info keys, in ``envs``, and their masks."""
    for key in INFO_KEYS + (("layout",) if "layout" in other else ()):
        assert np.array_equal(native[f"_{key}"][envs], other[f"_{key}"][envs]), key
        assert np.array_equal(native[key][envs], other[key][envs]), key


@pytest.mark.parametrize("mode", list(AutoresetMode))
def test_native_sync_and_async_play_the_same_games(env_id, mode):
    """Gymnasium's test_vector_env_equal, with the native env beside sync and async."""
    envs = {kind: make(kind, env_id, mode=mode) for kind in KINDS}
    native = envs["native"]
    assert isinstance(envs["sync"], SyncVectorEnv) and isinstance(envs["async"], AsyncVectorEnv)
    for other in envs.values():
        assert other.metadata["autoreset_mode"] == mode
        assert other.single_observation_space == native.single_observation_space
        assert other.action_space == native.action_space
        assert other.observation_space == native.observation_space
    first = {kind: env.reset(seed=[4, 8, 15]) for kind, env in envs.items()}
    everyone = np.ones(3, dtype=bool)
    for kind in ("sync", "async"):
        assert first[kind][0].tobytes() == first["native"][0].tobytes()
        assert_infos_equal(first["native"][1], first[kind][1], everyone)
    native.action_space.seed(0)
    ends = {"terminated": 0, "truncated": 0}
    for _ in range(260):
        actions = native.action_space.sample()
        results = {kind: env.step(actions) for kind, env in envs.items()}
        obs, reward, terminated, truncated, infos = results["native"]
        for kind in ("sync", "async"):
            obs1, reward1, terminated1, truncated1, infos1 = results[kind]
            assert obs.tobytes() == obs1.tobytes()
            assert np.array_equal(reward, reward1)
            assert np.array_equal(terminated, terminated1)
            assert np.array_equal(truncated, truncated1)
            assert_infos_equal(infos, infos1, everyone)
            if mode == AutoresetMode.SAME_STEP and (terminated | truncated).any():
                ended = terminated | truncated
                assert np.array_equal(infos["_final_obs"], infos1["_final_obs"])
                for env in np.flatnonzero(ended):
                    assert infos["final_obs"][env].tobytes() == infos1["final_obs"][env].tobytes()
                assert_infos_equal(infos["final_info"], infos1["final_info"], ended)
        ends["terminated"] += int(terminated.sum())
        ends["truncated"] += int(truncated.sum())
        if mode == AutoresetMode.DISABLED and (terminated | truncated).any():
            mask = terminated | truncated
            resets = {kind: env.reset(options={"reset_mask": mask}) for kind, env in envs.items()}
            for kind in ("sync", "async"):
                assert resets[kind][0].tobytes() == resets["native"][0].tobytes()
                assert_infos_equal(resets["native"][1], resets[kind][1], mask)
    assert ends["terminated"] > 0 and ends["truncated"] > 0  # both kinds of ends were compared
    for env in envs.values():
        env.close()


def test_the_native_envs_are_the_registered_vector_entry_points():
    assert isinstance(make("native", "Pinball-v0"), PinballVectorEnv)
    assert make("native", "PinballProcgen-v0").layouts is not None


def test_reset_and_step_types(env_id):
    """Gymnasium's test_reset_sync_vector_env and test_step_sync_vector_env."""
    env = make("native", env_id, render_mode=None)
    obs, infos = env.reset(seed=0)
    assert isinstance(obs, np.ndarray) and obs.dtype == env.observation_space.dtype
    assert obs.shape == (3, *env.single_observation_space.shape) == env.observation_space.shape
    assert obs in env.observation_space and isinstance(infos, dict)
    obs, rewards, terminations, truncations, infos = env.step(env.action_space.sample())
    assert obs in env.observation_space
    assert isinstance(rewards, np.ndarray) and rewards.dtype == np.float64
    for flags in (terminations, truncations):
        assert isinstance(flags, np.ndarray) and flags.dtype == np.bool_ and flags.shape == (3,)
    assert env.render() is None and env.call("render") == (None, None, None)


@pytest.mark.parametrize("mode", list(AutoresetMode))
def test_autoreset_metadata(mode):
    """Gymnasium's test_autoreset_metadata and test_make_vec_autoreset: the mode or its value."""
    for value in (mode, mode.value):
        env = make("native", "Pinball-v0", mode=value)
        assert env.metadata["autoreset_mode"] == mode and env.autoreset_mode == mode
    # The instance's metadata, not the class's (test_metadata_sync_vector_env).
    assert PinballVectorEnv.metadata["autoreset_mode"] == AutoresetMode.NEXT_STEP


def play_until_an_env_ends(env: VectorEnv, steps: int = 300) -> tuple:
    env.action_space.seed(1)
    for _ in range(steps):
        result = env.step(env.action_space.sample())
        if (result[2] | result[3]).any():
            return result
    pytest.fail("no episode ended")


@pytest.mark.parametrize("kind", KINDS)
def test_next_step_autoreset_resets_in_the_next_step(kind):
    """Gymnasium's test_autoreset_next_step: the step after an end returns the reset
    observation (the new game, on the plunger), reward 0, neither terminated nor truncated."""
    env = make(kind, "Pinball-v0")
    env.reset(seed=3)
    *_, terminated, truncated, _ = play_until_an_env_ends(env)
    ended = terminated | truncated
    obs, reward, terminated, truncated, infos = env.step(env.action_space.sample())
    assert not (terminated | truncated)[ended].any() and not reward[ended].any()
    assert (infos["frames"][ended] == 0).all() and (infos["score"][ended] == 0).all()
    assert (obs[ended, 9] == 1).all()  # one ball to play again
    env.close()


@pytest.mark.parametrize("kind", KINDS)
def test_same_step_autoreset_keeps_the_last_observation(kind):
    """Gymnasium's test_autoreset_within_step: the reset observation at once, the last one
    in final_obs, masked, and its info in final_info."""
    env = make(kind, "Pinball-v0", mode=AutoresetMode.SAME_STEP)
    env.reset(seed=3)
    obs, _, terminated, truncated, infos = play_until_an_env_ends(env)
    ended = terminated | truncated
    assert np.array_equal(infos["_final_obs"], ended) and np.array_equal(
        infos["_final_info"], ended
    )
    assert all(infos["final_obs"][env] is None for env in np.flatnonzero(~ended))
    for env_index in np.flatnonzero(ended):
        assert infos["final_obs"][env_index] in env.single_observation_space
    assert (infos["frames"][ended] == 0).all()  # the new game's info
    assert (infos["final_info"]["frames"][ended] > 0).all()  # the last game's
    assert (obs[ended, 9] == 1).all()
    env.close()


@pytest.mark.parametrize("kind", ["native", "sync"])
def test_disabled_autoreset_needs_a_masked_reset(kind):
    """Gymnasium's test_autoreset_disabled: nothing resets by itself; stepping an env that
    ended is SyncVectorEnv's AssertionError; a reset with the ended envs' mask goes on."""
    env = make(kind, "Pinball-v0", mode=AutoresetMode.DISABLED)
    env.reset(seed=3)
    obs, _, terminated, truncated, _ = play_until_an_env_ends(env)
    ended = terminated | truncated
    with pytest.raises(AssertionError):
        env.step(env.action_space.sample())
    again, _ = env.reset(options={"reset_mask": ended})
    assert again[~ended].tobytes() == obs[~ended].tobytes()  # the others as they were
    assert (again[ended, 9] == 1).all()
    _, _, terminated, truncated, infos = env.step(np.zeros(3, dtype=np.int64))
    assert (infos["frames"][ended] > 0).all()  # the new games are played
    env.close()


def test_partial_reset(env_id):
    """Gymnasium's test_partial_reset: a masked reset resets only the masked envs, with
    their seeds; the others keep their games (on procgen, the layouts drawn ahead too), the
    same in the native, sync and async envs."""
    envs = {kind: make(kind, env_id, mode=AutoresetMode.DISABLED) for kind in KINDS}
    mask = np.array([True, True, False])
    envs["native"].action_space.seed(123)
    for kind, env in envs.items():
        reset_obs, _ = env.reset(seed=[0, 1, 2])
        for _ in range(3):
            step_obs, *_ = env.step(np.array([1, 2, 3]))
        mask_obs, infos = env.reset(seed=[0, 1, 0], options={"reset_mask": mask})
        assert mask_obs[:2].tobytes() == reset_obs[:2].tobytes(), kind
        assert mask_obs[2].tobytes() == step_obs[2].tobytes(), kind
        assert infos["_score"].tolist() == [True, True, False], kind
    layouts = set()
    for _ in range(200):  # later games, their layouts drawn from the generators
        actions = envs["native"].action_space.sample()
        results = {kind: env.step(actions) for kind, env in envs.items()}
        for kind in ("sync", "async"):
            assert results[kind][0].tobytes() == results["native"][0].tobytes(), kind
        ended = results["native"][2] | results["native"][3]
        if ended.any():
            resets = {kind: env.reset(options={"reset_mask": ended}) for kind, env in envs.items()}
            for kind in ("sync", "async"):
                assert resets[kind][0].tobytes() == resets["native"][0].tobytes(), kind
            if "layout" in resets["native"][1]:
                layouts.update(resets["native"][1]["layout"][ended].tolist())
    assert len(layouts) == (2 if "Procgen" in env_id else 0)  # new games on both layouts
    for env in envs.values():
        env.close()


def reset_error(kind: str, error: type[Exception], message: str):
    """pytest.raises for a bad reset: Gymnasium's own vector envs check with asserts before 1.4
    (their words differ), the native env always as Gymnasium 1.4 does."""
    if kind != "native" and Version(gym.__version__) < Version("1.4"):
        return pytest.raises(AssertionError)
    return pytest.raises(error, match=re.escape(message))


@pytest.mark.parametrize("kind", KINDS)
def test_partial_reset_failure(kind):
    """Gymnasium's test_partial_reset_failure: its errors and messages, word for word."""
    env = make(kind, "Pinball-v0", mode=AutoresetMode.DISABLED)
    env.reset(options={"reset_mask": np.array([True, True, True])})
    for mask, shape in (([True], "(1,)"), ([True, True, False, False], "(4,)"),
                        ([[True, True, True]], "(1, 3)")):  # fmt: skip
        message = f"`options['reset_mask']` must have shape `(3,)`, got {shape}"
        with reset_error(kind, ValueError, message):
            env.reset(options={"reset_mask": np.array(mask)})
    message = (
        "`options['reset_mask']` must contain a boolean array with at least one True value, "
        "got reset_mask=[False False False]"
    )
    with reset_error(kind, ValueError, message):
        env.reset(options={"reset_mask": np.array([False, False, False])})
    for mask, dtype in (([1, 1, 0], "int64"), ([1.0, 1.0, 0.0], "float64")):
        message = f"`options['reset_mask']` must have `dtype=np.bool_`, got {dtype}"
        with reset_error(kind, TypeError, message):
            env.reset(options={"reset_mask": np.array(mask)})
    with reset_error(kind, TypeError, "must be a numpy array"):
        env.reset(options={"reset_mask": [True, False, True]})
    with reset_error(kind, ValueError, "the length must match num_envs=3"):
        env.reset(seed=[1, 2])
    env.close()


@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("action_type", ["discrete", "multibinary"])
def test_action_count_compatibility(kind, action_type):
    """Gymnasium's test_action_count_compatibility: too few or too many actions are a
    ValueError, a scalar action a TypeError."""
    env = make(kind, "Pinball-v0", num_envs=4, mode=AutoresetMode.DISABLED,
               action_type=action_type)  # fmt: skip
    env.reset(seed=0)
    actions = env.action_space.sample()
    obs, rewards, terminations, truncations, _ = env.step(actions)
    assert len(obs) == len(rewards) == len(terminations) == len(truncations) == 4
    with pytest.raises(ValueError):
        env.step(actions[:3])
    with pytest.raises(ValueError):
        env.step(np.concatenate([actions, actions[:1]]))
    with pytest.raises(TypeError):
        env.step(0)
    env.close()


@pytest.mark.parametrize(
    ("actions", "error"),
    [
        (None, TypeError),
        (1.5, TypeError),
        ("0000", TypeError),
        (np.array(["a", "b", "c"]), TypeError),
        ([0, None, 1], TypeError),
        (np.array([0, 1, 4]), ValueError),  # out of the action space
        (np.array([0, -1, 1]), ValueError),
        (np.array([0.5, 1.0, 1.0]), ValueError),
        ([[0, 1], [1], [2]], ValueError),  # ragged
        (np.zeros((3, 1), dtype=np.int64), ValueError),
    ],
)
def test_wrong_actions_are_refused_before_anything_changes(actions, error):
    env, reference = (make("native", "Pinball-v0", max_episode_steps=5) for _ in range(2))
    for vector in (env, reference):
        vector.reset(seed=0)
        for _ in range(5):  # the envs end: the next step resets them (NEXT_STEP)
            vector.step(np.zeros(3, dtype=np.int64))
    with pytest.raises(error):
        env.step(actions)
    for _ in range(3):
        one, two = env.step(np.ones(3, dtype=np.int64)), reference.step(np.ones(3, dtype=np.int64))
        assert one[0].tobytes() == two[0].tobytes() and np.array_equal(one[1], two[1])


def test_bool_actions_are_the_actions_zero_and_one():
    """MultiDiscrete holds bools (as 0 and 1): the native env takes them as those."""
    envs = [make("native", "Pinball-v0", num_envs=4) for _ in range(2)]
    for env in envs:
        env.reset(seed=9)
    actions = np.array([True, False, True, True])
    assert actions in envs[0].action_space
    for _ in range(40):
        one, two = envs[0].step(actions), envs[1].step(actions.astype(np.int64))
        assert one[0].tobytes() == two[0].tobytes()


@pytest.mark.parametrize("kind", KINDS)
def test_random_seeding_basics(kind):
    """Gymnasium's test_random_seeding_basics: np_random_seed is every env's seed, kept by a
    reset without one; a list seeds each env (None: kept)."""
    env = make(kind, "Pinball-v0")
    env.reset(seed=42)
    assert env.np_random_seed == (42, 43, 44)
    env.reset(seed=None)
    assert env.np_random_seed == (42, 43, 44)
    env.reset(seed=[7, None, 9])
    assert env.np_random_seed == (7, 43, 9)
    env.reset(seed=5, options={"reset_mask": np.array([False, True, False])})
    assert env.np_random_seed == (7, 6, 9)
    generators = env.np_random
    assert len(generators) == 3 and all(isinstance(g, np.random.Generator) for g in generators)
    env.close()


@pytest.mark.parametrize("kind", KINDS)
def test_seeds_before_any_seeded_reset_are_those_the_generators_come_from(kind):
    """Gymnasium's test_random_seeds_set_at_retrieval, for envs seeded at random: each env's
    seed, read before its first reset, is the one its generator was drawn from
    (seeding.np_random's)."""
    env = make(kind, "Pinball-v0")
    seeds = env.np_random_seed
    assert len(set(seeds)) == 3 and all(isinstance(seed, int) and seed >= 0 for seed in seeds)
    for seed, rng in zip(seeds, env.np_random, strict=True):
        assert rng.bit_generator.state == seeding.np_random(seed)[0].bit_generator.state
    env.reset()  # a reset without a seed keeps them
    assert env.np_random_seed == seeds
    env.close()


def test_a_generator_set_per_env_is_used_and_its_seed_unknown():
    env, reference = make("native", "Pinball-v0"), make("native", "Pinball-v0")
    reference.reset(seed=[10, 11, 12])
    env.reset(seed=0)
    env.set_attr("np_random", [seeding.np_random(s)[0] for s in (10, 11, 12)])
    assert env.np_random_seed == (-1, -1, -1)  # as Gymnasium's Env.np_random setter
    obs, _ = env.reset()
    assert obs.tobytes() == reference.reset(seed=[10, 11, 12])[0].tobytes()
    with pytest.raises(TypeError, match="Generator"):
        env.set_attr("np_random", 3)
    with pytest.raises(AttributeError, match="read-only"):
        env.set_attr("np_random_seed", 3)


@ASYNC_ERRORS_LOGGED
@pytest.mark.parametrize("kind", KINDS)
def test_set_attr_and_get_attr_of_a_users_attribute(kind):
    """Gymnasium's test_set_attr_sync_vector_env (its test envs' ``max_count``): per env."""
    env = make(kind, "Pinball-v0")
    env.set_attr("max_count", [2, 3, 3])
    assert env.get_attr("max_count") == (2, 3, 3)
    env.set_attr("max_count", 5)
    assert env.call("max_count") == (5, 5, 5)
    message = "Values must be a list or tuple with length equal to the number of environments."
    with pytest.raises(ValueError, match=re.escape(message)):
        env.set_attr("max_count", [1, 2])
    with pytest.raises(AttributeError):
        env.get_attr("no_such_attribute")
    env.close()


def test_per_env_attributes_are_each_envs_own(env_id):
    """get_attr of the per-env attributes gives what the single envs of a SyncVectorEnv have,
    and call("render") their frames, bitwise."""
    native = make("native", env_id, render_mode="rgb_array")
    sync = make("sync", env_id, render_mode="rgb_array")
    native.reset(seed=[3, 30, 300])
    sync.reset(seed=[3, 30, 300])
    actions = np.array([1, 2, 3])
    for _ in range(20):
        native.step(actions)
        sync.step(actions)
    names = ["table", "np_random_seed"] + (["layout"] if "Procgen" in env_id else [])
    for name in names:
        assert native.get_attr(name) == sync.get_attr(name), name
    assert native.get_attr("score") == tuple(int(g.score[0]) for g in sync.get_attr("game"))
    assert native.get_attr("balls_left") == (1, 1, 1)
    for frame, frame1 in zip(native.call("render"), sync.call("render"), strict=True):
        assert frame.tobytes() == frame1.tobytes()
    assert [f.tobytes() for f in native.render()] == [f.tobytes() for f in sync.render()]
    if "Procgen" in env_id:
        assert [t.name for t in native.get_attr("table")] == [
            f"procgen:{layout}" for layout in native.get_attr("layout")
        ]
    with pytest.raises(AttributeError, match="read-only"):
        native.set_attr("table", native.get_attr("table"))
    native.close()
    sync.close()


def test_shared_attributes_and_methods_of_the_vector_env():
    env = make("native", "Pinball-v0", num_envs=2)
    assert env.get_attr("render_mode") == (None, None)
    assert env.get_attr("game") == (env.game, env.game)
    env.set_attr("max_episode_steps", 4)  # the vector env's own: every env's time limit
    assert env.get_attr("max_episode_steps") == (4, 4)
    env.set_attr("max_episode_steps", [7, 7])  # one per env, all equal
    assert env.max_episode_steps == 7
    with pytest.raises(ValueError, match="shared by every env"):
        env.set_attr("max_episode_steps", [7, 8])
    with pytest.raises(ValueError, match="shared by every env"):
        env.set_env_attr(0, "max_episode_steps", 3)
    env.reset(seed=0)
    for _ in range(7):
        *_, truncated, _ = env.step(np.zeros(2, dtype=np.int64))
    assert truncated.all()
    assert env.call("env_attributes")[0].keys() >= {"table", "np_random", "render"}
    for name in ("reset", "step", "close"):
        message = f"Trying to call function `{name}` with `call`, use `{name}` directly instead."
        with pytest.raises(ValueError, match=re.escape(message)):
            env.call(name)
    with pytest.raises(ValueError, match="acting on every env"):
        env.call_env(0, "reset")
    assert env.env_attr(1, "render")() is None  # a per-env method, bound to its env
    with pytest.raises(IndexError):
        env.env_attr(2, "table")


@ASYNC_ERRORS_LOGGED
@pytest.mark.parametrize("kind", ["native", "async"])
def test_call_refuses_reset_step_and_close_as_async_does(kind):
    env = make(kind, "Pinball-v0", num_envs=2)
    with pytest.raises(ValueError, match="use `reset` directly"):
        env.call("reset")
    env.close()


def test_a_vector_env_is_closed_once_and_checks_its_autoreset_mode():
    env = make("native", "Pinball-v0")
    env.close()
    env.close()
    assert env.closed
    with pytest.raises(ValueError, match="autoreset_mode must be one of 'NextStep'"):
        PinballVectorEnv(num_envs=2, autoreset_mode="sometimes")
