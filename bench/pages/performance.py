"""The blocks of docs/PERFORMANCE.md and README.md that quote times, memory and headline figures: from
bench.timings.quickstart, bench.studies.paper, bench.timings.suite and python -m bench.timings.table's records, beside the authors' run times."""
from __future__ import annotations

import json

from bench.records import BENCH, QUICKSTART, RECORDS, SUITE, SUITE_CLAIMS, authors_seed_run_s, current_command
from bench.pages.results import (ENV_TITLES, ENVS, PRESET_RUN, commit_text, env_record, label, machine_text,
                                  rerun_command, seconds_text, stat_row)
from jaxbridge.utils import stats

MISSING = "_Not measured yet: `{command}`._\n"


def read(path) -> dict | None:
    return json.loads(path.read_text()) if path.is_file() else None


def minutes(seconds: float) -> str:
    return f"{seconds / 60:.0f} minutes" if seconds >= 90 else f"{seconds:.0f} s"


def busy_text(record: dict) -> str:
    """Each device's busy seconds as a share of the training's wall time (its schedule.json), where recorded."""
    schedule = record.get("schedule")
    if schedule is None:
        return "not recorded"
    return ", ".join(f"{s / schedule['wall_s']:.0%}" for s in schedule["busy_s"].values())


def quickstart_table() -> str:
    """Each env's `train.py --env E --num-seeds 8`: wall time, peak memory, and a seed-run's time against
    the authors' (one seed of ours over 100 cycles)."""
    records = read(QUICKSTART)
    if records is None:
        return MISSING.format(command="python -m bench.timings.quickstart")
    authors = authors_seed_run_s()
    lines = ["| command | approaches x seeds | wall time | peak RSS | each core busy | ours' s per seed-run | the authors' "
             "s per seed-run (ours) | ratio |", "|---|---|---|---|---|---|---|---|"]
    for env in ENVS:
        r = records.get(env)
        if r is None:
            continue
        ours = r.get("elapsed_s", {}).get("ours")  # ours' training seconds, its seeds one after another
        per_run, ratio = (f"{ours / 8:.1f}", f"{authors[env] / (ours / 8):,.0f}x") if ours else ("not recorded", "")
        lines.append(f"| `{current_command(r['command'])}` | {len(r['approaches'])} x 8 | {r['wall_s']:,.0f} s | "
                     f"{r['peak_rss_mib'] / 2**10:.2f} GiB | {busy_text(r)} | {per_run} | {authors[env]:,.0f} | {ratio} |")
    first = next(iter(records.values()))
    commits = {commit_text(r) for r in records.values()}
    code = commit_text(first) if len(commits) == 1 else "; ".join(f"{ENV_TITLES[e]} {commit_text(r)}" for e, r in records.items())
    lines += ["", f"Measured by `python -m bench.timings.quickstart` on {machine_text(first['machine'])}, {code}. Ours' "
              "seed-run is its training seconds in the experiment over its 8 seeds (one core each, beside the other "
              "approaches); the authors' is one seed of ours alone (docs/results/authors_times.csv; Coffee's run "
              "never finished, so its learning time). Each core busy: its busy seconds over the training's wall "
              "time (the run's schedule.json)."]
    return "\n".join(lines) + "\n"


PROFILE_PARTS = (("train_rollout", "training episodes"), ("observe", "into the buffer"),
                 ("learn", "learn (relabel + updates)"), ("test_rollout", "test episodes"), ("seed_cycle", "whole seed cycle"))


def maple_q_table(env: str = "doorknobs") -> str:
    """bench.timings.maple_q's record: each part of one seed's cycle in ms, per approach, and Maple Q's ratio to ours."""
    record = read(RECORDS / env / "maple_q_profile.json")
    if record is None:
        return MISSING.format(command=f"python -m bench.timings.maple_q --env {env}")
    figures, names = record["figures"], list(record["figures"])
    lines = ["| part of a seed's cycle | " + " | ".join(f"{label(n)} ms" for n in names) + f" | {label(names[-1])} / "
             f"{label(names[0])} |", "|---|" + "---|" * (len(names) + 1)]
    for part, title in PROFILE_PARTS:
        times = [figures[n]["ms"][part] for n in names]
        lines.append(f"| {title} | " + " | ".join(f"{t:.1f}" for t in times) + f" | {times[-1] / times[0]:.2f}x |")
    row = lambda title, key, of: (f"| {title} | " + " | ".join(f"{figures[n][of][key]:,}" for n in names) + " | |")
    lines += [row("observation width", "width", "observation"), row("entries stored per transition", "stored", "observation"),
              row("test env steps per cycle", "test_env_steps", "per_cycle"),
              row("test bridge decisions per cycle", "test_decisions", "per_cycle")]
    lines += ["", f"Measured by `{current_command(record['command'].strip())}` on {machine_text(record['machine'])}, {commit_text(record)}: "
              "seed 0 on one device, each part jitted alone after the warm-up, medians over rounds that time every "
              "approach's parts in turn."]
    return "\n".join(lines) + "\n"


def paper_table() -> str:
    """Each env's test-seed headline (bench.studies.paper): the time and memory of each of its steps."""
    lines = ["| command | training (approaches x 32 seeds) | `--preset authors` | oracle | sweep | total | peak RSS |",
             "|---|---|---|---|---|---|---|"]
    where = set()  # the headlines run hours, so their machine is often not the quick start's: say which it was
    for env in ENVS:
        record = env_record(env)
        if record is None:
            lines.append(f"| `python -m bench.studies.paper --env {env}` | not run yet | | | | | |")
            continue
        run, steps = record["run"], record["run"]["steps"]
        where.add(f"{machine_text(run['machine'])}, {commit_text(run)}")
        peak = max(steps[s]["peak_rss_mib"] for s in ("train", "train_authors_preset", "sweep"))
        lines.append(f"| `{rerun_command(run)}` | {seconds_text(steps['train'])} ({len(run['approaches'])} approaches) | "
                     f"{seconds_text(steps['train_authors_preset'])} | {steps['oracle']['wall_s']:,.0f} s | "
                     f"{seconds_text(steps['sweep'])} | {seconds_text(run)} | {peak / 2**10:.2f} GiB |")
    if where:
        lines += ["", "Measured on " + "; ".join(sorted(where)) + "."]
    return "\n".join(lines) + "\n"


def bench_rows(results: dict) -> str:
    """python -m bench.timings.table's figures as a markdown table, one row per env."""
    head = ("| env | env steps/s, 1 seed x 1 task | 8 seeds x 10 tasks | Q-updates/s (8 seeds) | s per cycle (8 seeds) "
            "| first cycle's compile s | programs compiled after it | tasks + plan tables s | peak RSS MiB (growth) |")
    lines = [head, "|---" * (head.count("|") - 1) + "|"]
    for env, r in results["envs"].items():
        meta, c, u = r["meta_policy"]["cases"], r["cycle"], r["updates"]
        lines.append(
            f"| {env} | {meta['1 seed x 1 task']['steps_per_s']:,.0f} | {meta['8 seeds x 10 tasks']['steps_per_s']:,.0f} "
            f"| {u['updates_per_s']:,.0f} ({u['updates']}/call) | {c['steady_s_per_cycle']:.3f} ({c['updates_per_cycle']} updates) "
            f"| {c['compile_s']:.1f} | {c['programs_compiled_after_first_cycle']} | {c['build_s']:.1f} "
            f"| {r['rss_peak_mib']:,.0f} (+{r['rss_growth_mib']:,.0f}) |")
    return "\n".join(lines)


def bench_table() -> str:
    """python -m bench.timings.table's table (bench/results.json) and how it was measured."""
    results = read(BENCH)
    if results is None:
        return MISSING.format(command="python -m bench.timings.table")
    commit = f", {commit_text(results)}" if "commit" in results else ""
    lines = [bench_rows(results), "", f"`python -m bench.timings.table` on {results['cpu_cores']} cores (jax {results['jax']}{commit}), "
             f"load {results['load_before'][0]} before; {results['settings']['measured_cycles']} measured cycles."]
    return "\n".join(lines) + "\n"


GPU = RECORDS / "gpu"  # bash bench/gpu.sh's files, as they came back from the GPU machine


def gpu_table() -> str:
    """bench/gpu.sh's bench.timings.scaling rows: per env and seed count, the build, first-cycle and steady-state
    times on one GPU, in blocks of all seeds or one seed at a time, and the 4-setting sweep's time."""
    run = read(GPU / "run.json")
    if run is None:
        return MISSING.format(command="bash bench/gpu.sh")
    lines = ["| env | seeds | block | tasks and plan tables (s) | first cycle (s) | s per cycle | 100 cycles (s), "
             "projected from the measured cycles | s per seed-run (projected) | the authors' s per seed-run / ours "
             "(projected) | peak GPU memory (GiB) |", "|---|" + "---|" * 9]
    for name in ("scaling_lsd", "scaling_doorknobs", "scaling_lsd_block1"):
        for r in read(GPU / f"{name}.json") or []:
            lines.append(f"| {ENV_TITLES[r['env']]} | {r['seeds']:,} | {r['block']:,} | {r['build_s']:.0f} | "
                         f"{r['first_cycle_s']:.0f} | {r['steady_s_per_cycle']:.3f} | {r['projected_100_cycles_s']:.0f} | "
                         f"{r['s_per_seed_run']:.2f} | {r['x_authors']:,.0f}x | {r['peak_device_bytes_so_far'] / 2**30:.1f} |")
    sweep = (GPU / "sweep.log").read_text().strip().splitlines()[-1]
    lines += ["", f"{sweep} (`train.py --seed-block 64`, learning rates 1e-3 and 3e-4 x epsilon decays 3.8e-5 and "
              "1e-4, one compiled program). Measured by `bash bench/gpu.sh` on " + run["machine"] + f", "
              f"{commit_text(run)}; {run['note']}. The files: docs/results/gpu/."]
    return "\n".join(lines) + "\n"


def suite_line() -> str:
    record, claims = read(SUITE), read(SUITE_CLAIMS)
    if record is None:
        return MISSING.format(command="python -m bench.timings.suite")
    wall = record["wall_s"]
    line = (f"`{current_command(record['command'])}`: {record['outcome'].split(' in ')[0]} in {wall:,.0f} s ({int(wall // 60)} min "
            f"{wall % 60:.0f} s; the target, the project's rule: under 8 minutes, "
            f"{stats.verdict(wall, None, 8 * 60, at_least=False)}) "
            f"on {machine_text(record['machine'])}, {commit_text(record)} (`python -m bench.timings.suite`).\n")
    if claims is None:
        return line + "\n" + MISSING.format(command="python -m bench.timings.suite --claims")
    return line + (f"\n`{current_command(claims['command'])}`: {claims['outcome'].split(' in ')[0]} in {claims['wall_s']:,.0f} s "
                   f"on {machine_text(claims['machine'])}, {commit_text(claims)} "
                   f"(`python -m bench.timings.suite --claims`).\n")


def readme_quickstart() -> str:
    """The README's sentence on what its first command trains, how long it takes, and what it prints."""
    record = (read(QUICKSTART) or {}).get("light_switch_door")
    if record is None:
        return MISSING.format(command="python -m bench.timings.quickstart")
    authors = authors_seed_run_s()["light_switch_door"]
    finals = ", ".join(f"{label(a)} {v:.2f}" for a, v in record["final_test_solve_rate"].items())
    return (f"The first line trains the paper's {len(record['approaches'])} approaches on Light Switch Door, 8 tuning "
            f"seeds (0-7) x 100 online learning cycles each (the paper's protocol), every approach's seeds in one "
            f"jitted computation sharded over the cores: {minutes(record['wall_s'])} ({record['wall_s']:,.0f} s, peak "
            f"RSS {record['peak_rss_mib'] / 2**10:.1f} GiB) on {machine_text(record['machine'])}; the authors' code "
            f"takes {authors / 3600:.1f} hours for one seed of one approach. It ends printing each approach's mean "
            f"test solve rate at cycle 100 ({finals} on the measuring machine; another CPU's floating-point "
            f"path moves single seeds) and writes `runs/light_switch_door/`:\n")


def protocol_note(record: dict) -> str:
    """Where the preset's runs are tested on another of the env's test-task distributions, which."""
    protocols = record["run"]["test_protocols"]
    return "" if protocols["authors_preset"] == protocols["main"] else f", on its {protocols['authors_preset']} test tasks"


def readme_env(env: str) -> str:
    """The README's line for `env`: its quick start's time and its test-seed headline."""
    quick = (read(QUICKSTART) or {}).get(env)
    record = env_record(env)
    trains = (f"`python train.py --env {env} --num-seeds 8` trains {', '.join(label(a) for a in quick['approaches'])} "
              f"in {minutes(quick['wall_s'])} on tuning seeds 0-7, ending with ours' mean test solve rate "
              f"{quick['final_test_solve_rate']['ours']:.2f} at cycle 100" if quick
              else f"`python train.py --env {env} --num-seeds 8`")
    if record is None:
        return f"* {ENV_TITLES[env]} (`{env}`): {trains}; its test-seed headline is not generated yet.\n"
    ours, preset = stat_row(record, "ours"), stat_row(record, PRESET_RUN)
    return (f"* {ENV_TITLES[env]} (`{env}`): {trains}. On the {ours['seeds']} test seeds ({record['run']['seeds']}) "
            f"ours' mean test solve rate is {ours['at10']} at cycle 10 and {ours['at100']} at cycle 100 (95% CIs); "
            f"with the authors' settings (`--preset authors`{protocol_note(record)}) {preset['at10']} and "
            f"{preset['at100']}; the oracle's "
            f"ceiling on the same tasks is {ours['ceiling']} (docs/RESULTS.md).\n")


BLOCKS = {"performance gpu": gpu_table, "performance maple q": maple_q_table, "performance quickstart": quickstart_table, "performance paper": paper_table,
          "performance bench": bench_table, "performance suite": suite_line, "readme quickstart": readme_quickstart,
          **{f"readme {env}": (lambda env=env: readme_env(env)) for env in ENVS}}
