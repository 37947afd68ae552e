"""The paper's executive: config, the planner/bridge meta-policy (Algorithm 1), hand-made bridges, task batches,
and the env contract check."""
