"""`--env NAME` for the command-line tools: a registered name or `package.module:Class`, checked once."""
from __future__ import annotations

import os
import sys

from envs_jax import NoveltyEnv, env_class, is_builtin
from jaxbridge.core.check_env import EnvContractError, check_env
from jaxbridge.utils.cli import UsageError


def load_env(spec: str) -> type[NoveltyEnv]:
    """The env class `spec` names; a plug-in (not built in) is checked against the contract first."""
    if os.getcwd() not in sys.path and "" not in sys.path:
        sys.path.insert(0, os.getcwd())  # `examples.locked_box:LockedBox` from the working directory
    try:
        env_cls = env_class(spec)
        if not is_builtin(spec):
            check_env(env_cls)
    except EnvContractError as err:
        raise UsageError(f"env {spec} breaks the env contract: {err}") from None
    except ValueError as err:
        raise UsageError(str(err)) from None
    return env_cls
