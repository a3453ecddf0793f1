"""Tasks: what an env asks of our robot (:class:`spl_env.tasks.base.Task`: start poses, scripted
robots, action mapping, observation encoders, reward and termination), each plugged into the
one step loop of :class:`spl_env.envs.core.SplEnv` by an env subclass naming it and its config."""
