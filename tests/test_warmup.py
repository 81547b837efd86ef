"""``warm_up`` compiles every kernel the tracking uses, so that no compilation is timed (the first run of a fresh
install reports the speed of the later ones)."""

import json
import subprocess
import sys
import textwrap

import pytest

from pftrack._numba import NUMBA_INSTALLED, numba_enabled

SCRIPT = textwrap.dedent("""
    import gc
    import json
    import sys
    from numba.core.registry import CPUDispatcher
    from pftrack.synth import Scene, SceneSpec, Target, occlusion_scene
    from pftrack.trackers.registry import create_tracker
    from pftrack.trackers.warmup import warm_up

    def signatures():
        return {o.py_func.__module__ + "." + o.py_func.__name__: len(o.signatures) for o in gc.get_objects()
                if isinstance(o, CPUDispatcher) and o.py_func.__module__.startswith("pftrack")}

    path = ((0, 120.0, 110.0), (29, 190.0, 130.0))
    scenes = [occlusion_scene(0, full=True)]  # tracking, loss, search, re-acquisition
    # a 160 x 200 target (lattice pitch 6 for fusion-pf: grey neighbourhoods) and a 70 x 90 one (grey blocks of 4 px)
    scenes += [SceneSpec(n_frames=30, targets=(Target(path=path, size=size),), gray=g)
               for size in ((160.0, 200.0), (70.0, 90.0)) for g in (False, True)]
    clips = [Scene(s) for s in scenes]
    frames = [[c.render(t)[0] for t in range(s.n_frames)] for c, s in zip(clips, scenes)]
    runs = json.loads(sys.argv[1])
    for name, params in runs:
        warm_up(name, params)
    before = signatures()
    for name, params in runs:
        for c, fr in zip(clips, frames):
            tr = create_tracker(name, seed=0, params=params)
            tr.init(fr[0], c.groundtruth(0)[0])
            for f in fr[1:]:
                tr.update(f)
    after = signatures()
    print({k: (before.get(k, 0), v) for k, v in after.items() if v != before.get(k, 0)})
""")


@pytest.mark.skipif(not (NUMBA_INSTALLED and numba_enabled()), reason="compiled kernels are off")
@pytest.mark.parametrize("runs", [[["fusion-pf", {}], ["color-pf", {}]],
                                  [["opencv-medianflow", {"monitor": "true"}]]])  # alone: the loss monitor's kernels
def test_warm_up_leaves_nothing_to_compile_while_tracking(runs):
    out = subprocess.run([sys.executable, "-c", SCRIPT, json.dumps(runs)], capture_output=True, text=True,
                         timeout=600)
    assert out.returncode == 0, out.stderr[-2000:]
    assert out.stdout.strip().splitlines()[-1] == "{}", out.stdout
