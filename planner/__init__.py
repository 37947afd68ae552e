"""The symbolic planner: STRIPS models, exact optimal search, and device plan tables."""
from planner.strips import Domain, GroundOperator, LiftedOperator, Problem, domain_pddl, ground, problem_pddl
from planner.tables import CompiledTask, PlanLookup, PlanTable, batched_plan_lookup, compile_task, stack_tables

__all__ = ['Domain', 'GroundOperator', 'LiftedOperator', 'Problem', 'domain_pddl', 'ground', 'problem_pddl', 'CompiledTask', 'PlanLookup', 'PlanTable', 'batched_plan_lookup', 'compile_task', 'stack_tables']
