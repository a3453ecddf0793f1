"""Robot bodies: the Nao (:mod:`spl_env.robots.nao`), its command and its one head mapping; the
env core (:class:`spl_env.envs.core.SplEnv`) puts our robot and the scripted ones in the world
and drives each step with a :class:`~spl_env.robots.nao.NaoCommand` from the task."""
