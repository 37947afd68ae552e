"""The symbolic planner: STRIPS models, PDDL text both ways, exact optimal search, heuristic search, and
device plan tables."""
from planner.heuristic import Relaxation, SearchResult, astar, h_ff, h_max
from planner.pddl import PDDLError, read_domain, read_problem
from planner.strips import Domain, GroundOperator, LiftedOperator, Problem, domain_pddl, ground, problem_pddl
from planner.tables import CompiledTask, PlanLookup, PlanTable, batched_plan_lookup, compile_task, stack_tables

__all__ = ['Domain', 'GroundOperator', 'LiftedOperator', 'Problem', 'domain_pddl', 'ground', 'problem_pddl',
           'PDDLError', 'read_domain', 'read_problem', 'Relaxation', 'SearchResult', 'astar', 'h_ff', 'h_max',
           'CompiledTask', 'PlanLookup', 'PlanTable', 'batched_plan_lookup', 'compile_task', 'stack_tables']
