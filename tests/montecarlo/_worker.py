"""Subprocess side of the scale-out and kill-and-resume tests: ``python -m tests.montecarlo._worker MODE ...``.

* ``devices OUT``: a Monte Carlo on however many devices ``XLA_FLAGS`` gives; statistics → ``OUT`` (npz);
* ``distributed PROCESS_ID PORT OUT DIR``: the same as one of two ``jax.distributed`` processes on
  127.0.0.1 (process 0 checkpoints into ``DIR``);
* ``sweep DIR DELAY``: a checkpointed sweep that sleeps ``DELAY`` s after each chunk (to be killed).
"""

import sys

N, KEY, CHUNK = 30_500, 21, 10_000
SWEEP_N, SWEEP_CHUNK = 12_000, 2_000


def _save(path, result):
    import jax
    import numpy as np

    np.savez(
        path, __devices__=np.array(len(jax.devices())), __processes__=np.array(jax.process_count()), **result.arrays()
    )


def main(argv):
    mode = argv[0]
    if mode == "distributed":
        import jax

        jax.distributed.initialize(
            f"127.0.0.1:{argv[2]}", num_processes=2, process_id=int(argv[1]), initialization_timeout=120
        )
    import jaxsim.montecarlo as mc
    from tests.montecarlo._demo import SPACE, demo_fn, slow_progress

    if mode == "devices":
        _save(argv[1], mc.monte_carlo(demo_fn, SPACE, N, KEY, chunk_size=CHUNK))
    elif mode == "distributed":
        out = argv[4] if argv[1] == "0" else None
        _save(argv[3], mc.monte_carlo(demo_fn, SPACE, N, KEY, chunk_size=CHUNK, out=out))
    elif mode == "sweep":
        design = mc.grid({"fixed": (1.0, 3.0, 2)})
        mc.sweep(
            demo_fn,
            SPACE,
            design,
            SWEEP_N,
            KEY,
            chunk_size=SWEEP_CHUNK,
            out=argv[1],
            progress=slow_progress(float(argv[2])),
        )
    else:
        raise SystemExit(f"unknown mode {mode}")


if __name__ == "__main__":
    main(sys.argv[1:])
