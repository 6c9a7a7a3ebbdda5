"""Gymnasium's contract for an environment and a vector environment, as rules a test can
run: what gymnasium.utils.env_checker.check_env checks (its spaces, reset's seed and
options, np_random's seeding, step's return types and determinism, observations inside
the observation space, rendering, closing) and what Gymnasium 1.x's vector API asks of a
VectorEnv (batched spaces, autoreset_mode in its metadata, info arrays with their "_key"
masks, the final observation and info of a same-step autoreset). Written from Gymnasium's
documentation and env_checker's rules; Gymnasium itself is not in Debian 12.

Each check raises AssertionError naming the rule it broke. check_env's warnings about
infinite Box bounds are not rules here: a target's position and its distance are unbounded
(a terminal one lies beyond the grid, a placed one anywhere), and said so in the spaces.
"""
import copy
import inspect

import numpy as np

RULES = {
    "spaces": "action_space and observation_space are spaces with contains() and sample()",
    "attributes": "metadata (a dict with render_modes), render_mode, spec, unwrapped and np_random",
    "reset signature": "reset takes seed= and options= as keywords",
    "reset return": "reset returns (observation, info) with info a dict",
    "observation inside": "every observation, terminal ones included, lies in observation_space",
    "seeded reset": "reset(seed=s) twice gives the same observation and seeds np_random alike",
    "unseeded reset": "reset() after reset(seed=s) does not seed np_random again",
    "step return": "step returns (observation, float reward, bool terminated, bool truncated, dict info)",
    "step determinism": "the same seed and actions give the same steps",
    "every action valid": "every element of action_space is a valid action",
    "action mask": "info['action_mask'] is int8 of the action space's size and Discrete.sample(mask=) takes it",
    "options": "reset's options place the start",
    "render": "render() in rgb_array mode returns uint8 (H, W, 3)",
    "close": "close() may be called, and called again",
    "vector spaces": "action_space and observation_space are the single spaces batched num_envs times",
    "vector autoreset": "metadata['autoreset_mode'] names the autoreset mode (same step here)",
    "vector info": "each info key an array over the environments with a boolean '_key' mask beside it",
    "final observation": "an ended environment's last observation and info are kept in final_obs and final_info",
}


def rule(name, condition, detail=""):
    if not condition:
        raise AssertionError(f"Gymnasium rule '{name}' ({RULES[name]}) broken" + (f": {detail}" if detail else ""))


def equal(a, b):
    """Gymnasium's data_equivalence: the same structure, dtypes and values."""
    if type(a) is not type(b) and not (isinstance(a, (int, np.integer)) and isinstance(b, (int, np.integer))):
        return False
    if isinstance(a, dict):
        return a.keys() == b.keys() and all(equal(a[k], b[k]) for k in a)
    if isinstance(a, (tuple, list)):
        return len(a) == len(b) and all(equal(x, y) for x, y in zip(a, b))
    if isinstance(a, np.ndarray):
        return a.dtype == b.dtype and a.shape == b.shape and np.array_equal(a, b, equal_nan=True)
    return a == b


def is_space(space):
    return all(callable(getattr(space, m, None)) for m in ("contains", "sample", "seed"))


def legal(info, rng):
    """An action the mask allows (single environment)."""
    return int(rng.choice(np.flatnonzero(info["action_mask"])))


def check_attributes(env):
    rule("spaces", is_space(env.action_space) and is_space(env.observation_space))
    rule("attributes", isinstance(env.metadata, dict) and isinstance(env.metadata.get("render_modes"), list))
    rule("attributes", env.render_mode is None or env.render_mode in env.metadata["render_modes"],
         f"render_mode {env.render_mode!r}")
    rule("attributes", hasattr(env, "spec"), "no spec")
    rule("attributes", env.unwrapped is env, "unwrapped is not the environment")
    rule("attributes", isinstance(env.np_random, np.random.Generator), f"np_random is {type(env.np_random)}")


def check_reset(env, seed):
    parameters = inspect.signature(env.reset).parameters
    rule("reset signature", "seed" in parameters and "options" in parameters, f"parameters {list(parameters)}")
    result = env.reset(seed=seed)
    rule("reset return", isinstance(result, tuple) and len(result) == 2 and isinstance(result[1], dict))
    obs1, _ = result
    rule("observation inside", env.observation_space.contains(obs1), f"reset's {obs1}")
    rng1 = copy.deepcopy(env.np_random.bit_generator.state)
    rule("seeded reset", getattr(env, "np_random_seed", seed) == seed, "np_random_seed is not the seed")
    obs2, _ = env.reset(seed=seed)
    rule("seeded reset", equal(obs1, obs2), f"{obs1} then {obs2}")
    rule("seeded reset", env.np_random.bit_generator.state == rng1, "np_random differs after the same seed")
    env.reset(seed=seed + 1)
    rule("seeded reset", env.np_random.bit_generator.state != rng1, "np_random is the same for another seed")
    env.reset(seed=seed)
    env.np_random.random()
    drawn = copy.deepcopy(env.np_random.bit_generator.state)
    env.reset()
    rule("unseeded reset", env.np_random.bit_generator.state == drawn, "reset() seeded np_random again")


def check_steps(env, seed, episodes, starts=(None,)):
    """Plays `episodes` episodes with the mask's actions, started in turn from `starts`
    (reset's options); every observation must lie in the space and every step return
    Gymnasium's types. Returns how many episodes terminated."""
    rng = np.random.default_rng(seed)
    terminated_episodes = 0
    for episode in range(episodes):
        obs, info = env.reset(seed=seed + episode, options=starts[episode % len(starts)])
        check_mask(env, info)
        for _ in range(1000):
            result = env.step(legal(info, rng))
            rule("step return", isinstance(result, tuple) and len(result) == 5)
            obs, reward, terminated, truncated, info = result
            rule("step return", isinstance(reward, (float, int, np.floating, np.integer)) and np.isfinite(reward),
                 f"reward {reward!r}")
            rule("step return", isinstance(terminated, (bool, np.bool_)) and isinstance(truncated, (bool, np.bool_)),
                 f"terminated {terminated!r}, truncated {truncated!r}")
            rule("step return", isinstance(info, dict))
            rule("observation inside", env.observation_space.contains(obs),
                 f"{'terminal' if terminated else 'truncated' if truncated else 'a'} observation {obs}")
            check_mask(env, info)
            if terminated or truncated:
                terminated_episodes += bool(terminated)
                break
    return terminated_episodes


def check_mask(env, info):
    mask = info["action_mask"]
    rule("action mask", isinstance(mask, np.ndarray) and mask.dtype == np.int8 and mask.shape == (env.action_space.n,),
         f"found {getattr(mask, 'dtype', type(mask))} {getattr(mask, 'shape', '')}")
    picked = env.action_space.sample(mask=mask)
    rule("action mask", mask[int(picked)] == 1, f"sample(mask=) gave {picked}")


def check_step_determinism(env, seed):
    def play():
        env.action_space.seed(seed)
        env.reset(seed=seed)
        return [env.step(env.action_space.sample()) for _ in range(3)]

    try:
        first, second = play(), play()
    except Exception as error:  # noqa: BLE001 - any refusal breaks the rule
        rule("every action valid", False, f"{type(error).__name__}: {error}")
    for a, b in zip(first, second):
        rule("step determinism", equal(a[0], b[0]) and a[1:4] == b[1:4] and equal(a[4], b[4]), f"{a} then {b}")


def check_every_action(env, seed):
    """Every index of the action space, played from one start, is accepted."""
    for action in range(int(env.action_space.n)):
        env.reset(seed=seed)
        try:
            env.step(np.int64(action))
        except Exception as error:  # noqa: BLE001
            rule("every action valid", False, f"action {action}: {type(error).__name__}: {error}")


def check_options(env, seed):
    obs, _ = env.reset(seed=seed)
    state = (int(obs["state"]) + 1) % int(env.observation_space["state"].n)
    placed, _ = env.reset(seed=seed, options={"state": state, "target": obs["target"] * 0.5})
    rule("options", placed["state"] == state and np.allclose(placed["target"], obs["target"] * 0.5, atol=1e-6),
         f"asked state {state}, target {obs['target'] * 0.5}; found {placed}")


def check_render_and_close(env):
    if env.render_mode == "rgb_array":
        image = env.render()
        rule("render", isinstance(image, np.ndarray) and image.dtype == np.uint8 and image.ndim == 3
             and image.shape[2] == 3)
    env.close()
    env.close()
    rule("close", True)


def check_env(env, seed=11, episodes=20, starts=(None,)):
    """Every rule for a single environment; the episodes start in turn from `starts`
    (reset's options). Returns how many of the episodes terminated (the caller asks for
    terminal observations to have been seen)."""
    check_attributes(env)
    check_reset(env, seed)
    check_options(env, seed)
    terminated = check_steps(env, seed, episodes, starts)
    check_step_determinism(env, seed)
    check_every_action(env, seed)
    check_render_and_close(env)
    return terminated


def check_vector_env(vec, batch_space, single_env, seed=5, steps=120):
    """Every rule for a vector environment. `batch_space` is Gymnasium's (or the module's
    stand-in); `single_env` makes one environment of the same behaviour and options, whose
    episodes the vector's are compared with: an ended environment's final observation must
    be the single environment's terminal one. Returns how many episodes ended."""
    n = vec.num_envs
    check_attributes(vec)
    rule("vector spaces", vec.action_space == batch_space(vec.single_action_space, n),
         f"{vec.action_space} for {n} of {vec.single_action_space}")
    rule("vector spaces", vec.observation_space == batch_space(vec.single_observation_space, n),
         f"{vec.observation_space}")
    mode = vec.metadata.get("autoreset_mode")
    rule("vector autoreset", getattr(mode, "value", None) == "SameStep", f"found {mode!r}")
    obs, info = vec.reset(seed=seed)
    rule("observation inside", vec.observation_space.contains(obs), f"reset's {obs}")
    check_vector_info(info, n, ("action_mask",))
    singles = [single_env() for _ in range(n)]
    for i, env in enumerate(singles):
        env.reset(seed=seed + i)
    rng = np.random.default_rng(seed)
    ended = 0
    for _ in range(steps):
        actions = np.array([rng.choice(np.flatnonzero(m)) for m in info["action_mask"]], dtype=np.int64)
        obs, reward, terminated, truncated, info = vec.step(actions)
        rule("step return", isinstance(reward, np.ndarray) and reward.shape == (n,) and reward.dtype.kind == "f")
        rule("step return", terminated.dtype == np.bool_ and truncated.dtype == np.bool_ and terminated.shape == (n,))
        rule("observation inside", vec.observation_space.contains(obs), f"{obs}")
        check_vector_info(info, n, ("action_mask", "success"))
        rule("action mask", info["action_mask"].dtype == np.int8)
        done = terminated | truncated
        rule("final observation", "final_obs" in info and "_final_obs" in info and "final_info" in info,
             f"info has {sorted(info)}")
        rule("final observation", np.array_equal(info["_final_obs"], done) and np.array_equal(info["_final_info"], done),
             f"_final_obs {info['_final_obs']} where episodes ended {done}")
        for i, env in enumerate(singles):
            last, r, te, tr, last_info = env.step(int(actions[i]))
            rule("step determinism", (r, te, tr) == (reward[i], terminated[i], truncated[i]))
            if te or tr:
                ended += 1
                final = {k: v[i] for k, v in info["final_obs"].items()}
                rule("observation inside", vec.single_observation_space.contains(final), f"final {final}")
                rule("final observation", int(final["state"]) == last["state"]
                     and np.array_equal(final["target"], last["target"])
                     and np.array_equal(final["coordinates"], last["coordinates"]),
                     f"environment {i}: final_obs {final}, the episode ended at {last}")
                rule("final observation", np.array_equal(info["final_info"]["action_mask"][i], last_info["action_mask"])
                     and info["final_info"]["success"][i] == last_info["success"])
                env._episodes.reset(0, None)  # restarted as the vector restarts it: the same stream
                env._last = None
    vec.close()
    vec.close()
    return ended


def check_vector_info(info, n, keys):
    rule("vector info", isinstance(info, dict))
    for key in keys:
        rule("vector info", key in info and len(info[key]) == n, f"no array '{key}' over {n} environments")
        mask = info.get("_" + key)
        rule("vector info", isinstance(mask, np.ndarray) and mask.dtype == np.bool_ and mask.shape == (n,),
             f"'_{key}' is {mask!r}")
