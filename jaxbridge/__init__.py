"""jaxbridge: planner + learned bridge policy, vectorised in JAX."""
