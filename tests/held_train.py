"""train.py that stops right after sealing checkpoint N (N = 0: before its first cycle, still starting
up), writes DIR/held and waits until DIR/release exists: a test can then kill it, interrupt it, or run
a second process against its locked directory, at a known step, whatever the machine's speed.

    python tests/held_train.py N DIR TRAIN_ARGS...
"""
import runpy
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    hold_after, signals, args = int(sys.argv[1]), Path(sys.argv[2]), sys.argv[3:]
    sys.path.insert(0, str(ROOT))
    from jaxbridge.learn.online import Cycle
    from jaxbridge.run import checkpoint

    def hold() -> None:
        (signals / "held").write_text(str(hold_after))
        deadline = time.time() + 600
        while not (signals / "release").exists():  # released by the test, or killed here
            if time.time() > deadline:
                sys.exit("held_train: never released")
            time.sleep(0.05)

    save, first_cycle = checkpoint.save, Cycle.__call__

    def save_then_hold(directory, step, state, record, keep=()):
        save(directory, step, state, record, keep)
        if step == hold_after:
            hold()

    def hold_then_cycle(self, learners):
        if not (signals / "held").exists():
            hold()
        return first_cycle(self, learners)

    if hold_after == 0:
        Cycle.__call__ = hold_then_cycle
    else:
        checkpoint.save = save_then_hold
    sys.argv = [str(ROOT / "train.py"), *args]
    runpy.run_path(str(ROOT / "train.py"), run_name="__main__")


if __name__ == "__main__":
    main()
