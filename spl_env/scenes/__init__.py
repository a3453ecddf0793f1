"""Static worlds robots play in: the SPL field (:mod:`spl_env.scenes.spl_field`), which the env
core builds once per env as a :class:`~spl_env.scenes.spl_field.SplFieldScene` and asks for the
ground truth (pole codes and positions, obstacles, the ball)."""
