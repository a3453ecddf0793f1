"""Record SPL/ActiveVision-v0 reference rollouts (run on the commit before the reshaping)."""
import sys
import numpy as np
import gymnasium as gym
import spl_env  # noqa: F401

CASES = {
    "rendered": {},
    "rendered_colour_lighting": {"frontend": "colour", "randomise_lighting": True, "body_behaviour": "square"},
    "geometric": {"camera_mode": "geometric", "frontend": "colour"},
}
STEPS = 40
out = {}
for name, kwargs in CASES.items():
    env = gym.make("SPL/ActiveVision-v0", **kwargs)
    actions = np.random.default_rng(7).uniform(-1, 1, size=(STEPS, 2)).astype(np.float32)
    obs, info = env.reset(seed=11)
    keys = sorted(obs)
    obs_rows = [np.concatenate([obs[k] for k in keys])]
    poses = [info["perception"]["pose"]]
    truth = [info["ground_truth"]["robot_pose"]]
    rewards = []
    for a in actions:
        obs, r, term, trunc, info = env.step(a)
        obs_rows.append(np.concatenate([obs[k] for k in keys]))
        poses.append(info["perception"]["pose"])
        truth.append(info["ground_truth"]["robot_pose"])
        rewards.append(r)
    env.close()
    out[f"{name}__actions"] = actions
    out[f"{name}__observations"] = np.array(obs_rows)
    out[f"{name}__pose"] = np.array(poses)
    out[f"{name}__true_pose"] = np.array(truth)
    out[f"{name}__rewards"] = np.array(rewards)
    out["keys"] = np.array(keys)
    print(name, np.array(poses)[-1], np.array(truth)[-1])
np.savez_compressed(sys.argv[1], **out)
