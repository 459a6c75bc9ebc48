"""A warm start for actor-critic agents: behaviour cloning of the heuristic.

With ``imitation_steps`` > 0 in a config, before it learns, the heuristic
(``pinball_env.players.HeuristicPolicy``) plays the training games for that many env steps
(summed over the envs), through the training env chain, so that ``VecNormalize``'s statistics
start from its games. The policy is then fitted to the heuristic's actions (cross-entropy) and
the value to the discounted returns of its games (mean squared error, the rewards normalised
as the algorithm will see them), ``imitation_epochs`` passes in minibatches at
``imitation_learning_rate``. Learning goes on from there. The teacher's steps count in
``max_minutes`` and in ``time/frames``, not in ``total_timesteps``.

The heuristic is the bar the agent has to beat: copying it is where learning starts, not
the result; the evaluation plays the learned policy alone.

With ``kl_anchor_coef`` > 0, :class:`KLAnchor` keeps the learner near that start: after each update,
one pass over the states of the rollout the update learned from lowers ``kl_anchor_coef`` times
KL(warm start || policy), the warm start's action distribution against the policy's. Fine-tuning
from a copy forgets what the copy knew on states the gradient says little about (Wolczyk et al.
2024, "Fine-tuning reinforcement learning models is secretly a forgetting mitigation problem");
the pull is proportional to how far the policy has gone, so a drift of little evidence is undone
while a steady advantage still moves it.
"""

import copy
import time
from typing import Any

import numpy as np

from agents.envs import FrameCounter
from agents.rollouts import HeuristicPlayers

BATCH_SIZE = 512


def teacher_games(venv: Any, steps: int, stop: Any = False) -> dict[str, Any]:
    """The heuristic's play for ``steps`` steps of each env of ``venv`` (an SB3 VecEnv,
    possibly ``VecNormalize``, whose statistics learn from it): per step and env, the raw
    observation, the action, the raw reward and whether the game ended. Also ``frames``: the
    frames played, summed over the envs. Fewer steps (at least one) once ``stop`` is true."""
    n = venv.num_envs
    game = venv.get_attr("game")[0]
    players = HeuristicPlayers(game.world)
    raw = getattr(venv, "get_original_obs", None)
    obs = venv.reset()
    observations, actions, rewards, dones = [], [], [], []
    frames = FrameCounter(venv)
    for step in range(steps):
        if step and stop:
            break
        observations.append(raw() if raw else obs)
        infos = game.infos()  # the env's infos (with the cabinet's keys on Pinball-v1)
        action = np.array([
            players(env, {key: values[env] for key, values in infos.items()})
            for env in range(n)
        ])  # fmt: skip
        obs, reward, done, _ = venv.step(action)
        actions.append(action)
        rewards.append(venv.get_original_reward() if raw else reward)
        dones.append(done)
        for env in np.flatnonzero(done):  # a new game (maybe on a new table): a new player
            players.new_game(env)
    return {
        "obs": np.stack(observations),
        "actions": np.stack(actions),
        "rewards": np.stack(rewards),
        "dones": np.stack(dones),
        "frames": frames.frames,
    }


def discounted_returns(rewards: np.ndarray, dones: np.ndarray, gamma: float) -> np.ndarray:
    """(steps, envs) returns: each reward plus ``gamma`` times the next return, restarting at
    each game's end; the last step's return is its reward (no bootstrap)."""
    returns = np.zeros_like(rewards, dtype=np.float64)
    following = np.zeros(rewards.shape[1])
    for step in range(len(rewards) - 1, -1, -1):
        following = rewards[step] + gamma * following * (1.0 - dones[step])
        returns[step] = following
    return returns


def imitate(
    model: Any, venv: Any, steps: int, epochs: int, seed: int, stop: Any = False,
    learning_rate: float | None = None,
) -> dict[str, float]:  # fmt: skip
    """Play ``steps`` env steps of the heuristic in ``venv`` and fit ``model``'s policy and value
    to them (see the module's docstring), at ``learning_rate`` (None: the rate its optimizer
    has); returns the fit's figures. Once ``stop`` (a ``StopRequest``) is true, the games and
    the fit end early: the model keeps what it fitted."""

    start = time.monotonic()
    games = teacher_games(venv, max(1, steps // venv.num_envs), stop)
    normalize = getattr(venv, "normalize_obs", None)
    obs = games["obs"].reshape(-1, *games["obs"].shape[2:])
    obs = normalize(obs) if normalize else obs
    rewards = games["rewards"]
    if hasattr(venv, "normalize_reward"):
        rewards = venv.normalize_reward(rewards)
    returns = discounted_returns(rewards, games["dones"], model.gamma).reshape(-1)
    actions = games["actions"].reshape(-1)
    fitted = fit_policy(model.policy, obs, actions, epochs, seed, returns=returns,
                        vf_coef=getattr(model, "vf_coef", 0.5), learning_rate=learning_rate,
                        stop=stop)  # fmt: skip
    return {"steps": len(actions), "frames": games["frames"], **fitted,
            "seconds": time.monotonic() - start}  # fmt: skip


def fit_policy(
    policy: Any, obs: np.ndarray, actions: np.ndarray, epochs: int, seed: int,
    returns: np.ndarray | None = None, vf_coef: float = 0.5, learning_rate: float | None = None,
    stop: Any = False, batch_size: int = BATCH_SIZE, class_weights: np.ndarray | None = None,
) -> dict[str, float]:  # fmt: skip
    """Fit an actor-critic ``policy`` (stable-baselines3's) to a teacher: its actions to
    ``actions`` (cross-entropy) and, given ``returns``, its value to them (mean squared error,
    weighed by ``vf_coef``) in ``epochs`` passes over (``obs``, already normalised as the
    policy sees them) in shuffled minibatches, with its own optimizer (at ``learning_rate``
    meanwhile; None: its rate); with ``class_weights`` (one per action), each step's
    cross-entropy weighed by its action's. Returns the fit's accuracy (and value loss) after
    it."""
    import torch

    policy.set_training_mode(True)
    device = policy.device
    obs_t = torch.as_tensor(obs, dtype=torch.float32, device=device)
    actions_t = torch.as_tensor(actions, device=device)
    returns_t = None if returns is None else torch.as_tensor(returns, dtype=torch.float32,
                                                             device=device)  # fmt: skip
    weights_t = (
        None
        if class_weights is None
        else torch.as_tensor(class_weights, dtype=torch.float32, device=device)
    )
    rng = np.random.default_rng(seed)
    rates = [group["lr"] for group in policy.optimizer.param_groups]
    if learning_rate is not None:  # (the algorithm sets its own rate again as it learns)
        for group in policy.optimizer.param_groups:
            group["lr"] = learning_rate
    for _ in range(epochs):
        order = rng.permutation(len(actions))
        for first in range(0, len(order), batch_size):
            if stop:
                break
            batch = torch.as_tensor(order[first : first + batch_size], device=device)
            values, log_prob, _ = policy.evaluate_actions(obs_t[batch], actions_t[batch])
            if weights_t is None:
                loss = -log_prob.mean()
            else:
                weight = weights_t[actions_t[batch]]
                loss = -(weight * log_prob).sum() / weight.sum()
            if returns_t is not None:
                loss = loss + vf_coef * torch.nn.functional.mse_loss(values.flatten(),
                                                                     returns_t[batch])  # fmt: skip
            policy.optimizer.zero_grad()
            loss.backward()
            torch.nn.utils.clip_grad_norm_(policy.parameters(), 0.5)
            policy.optimizer.step()
    for group, rate in zip(policy.optimizer.param_groups, rates, strict=True):
        group["lr"] = rate
    policy.set_training_mode(False)
    with torch.no_grad():
        chosen = policy.get_distribution(obs_t).distribution.probs.argmax(dim=1)
        fitted = {"accuracy": float((chosen == actions_t).float().mean())}
        if returns_t is not None:
            values = policy.predict_values(obs_t).flatten()
            fitted["value_loss"] = float(torch.mean((values - returns_t) ** 2))
    return fitted


class KLAnchor:
    """The pull towards the warm start (see the module's docstring) of an actor-critic with
    discrete actions. ``reference`` is the warm start's policy (a frozen copy is kept);
    :meth:`remember` takes a rollout's states, :meth:`pull` fits the model's policy to the
    reference's actions on them, one pass in minibatches of ``batch_size``, with the policy's
    own optimizer at its current rate (so the pull decays with the algorithm's schedule)."""

    def __init__(self, reference: Any, coef: float, batch_size: int, seed: int,
                 max_grad_norm: float = 0.5) -> None:  # fmt: skip
        self.reference = copy.deepcopy(reference)
        self.reference.set_training_mode(False)
        for parameter in self.reference.parameters():
            parameter.requires_grad_(False)
        self.coef, self.batch_size, self.max_grad_norm = coef, batch_size, max_grad_norm
        self.rng = np.random.default_rng(seed)
        self.states: Any = None

    def remember(self, observations: np.ndarray) -> None:
        """The states of a rollout, ``(steps, envs, *shape)`` as the rollout buffer holds them."""
        self.states = np.array(observations, dtype=np.float32).reshape(-1, *observations.shape[2:])

    def divergence(self, policy: Any, states: Any = None) -> float:
        """The mean KL(warm start || ``policy``) over ``states`` (default: those remembered)."""
        import torch

        states = self._tensor(policy, self.states if states is None else states)
        with torch.no_grad():
            return float(self._kl(policy, states, self._log_probs(self.reference, states)))

    def pull(self, policy: Any) -> float | None:
        """One pass of the pull over the remembered states (then forgotten); returns the mean
        KL before it, or None with no states remembered."""
        import torch

        if self.states is None:
            return None
        states = self._tensor(policy, self.states)
        self.states = None
        with torch.no_grad():
            reference = self._log_probs(self.reference, states)
            before = float(self._kl(policy, states, reference))
        policy.set_training_mode(True)
        order = torch.as_tensor(self.rng.permutation(len(states)), device=policy.device)
        for first in range(0, len(order), self.batch_size):
            batch = order[first : first + self.batch_size]
            loss = self.coef * self._kl(policy, states[batch], reference[batch])
            policy.optimizer.zero_grad()
            loss.backward()
            torch.nn.utils.clip_grad_norm_(policy.parameters(), self.max_grad_norm)
            policy.optimizer.step()
        policy.set_training_mode(False)
        return before

    @staticmethod
    def _tensor(policy: Any, states: np.ndarray) -> Any:
        import torch

        return torch.as_tensor(states, dtype=torch.float32, device=policy.device)

    @staticmethod
    def _log_probs(policy: Any, states: Any) -> Any:
        return policy.get_distribution(states).distribution.logits  # (normalised log-probs)

    @classmethod
    def _kl(cls, policy: Any, states: Any, reference: Any) -> Any:
        log_probs = cls._log_probs(policy, states)
        return (reference.exp() * (reference - log_probs)).sum(dim=1).mean()
