"""A refused search candidate gives way to the next (pftrack.trackers.vetoes, ``search_retries``)."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

import pftrack
from pftrack.trackers.vetoes import SearchCandidates, VetoMixin, near_mask


class _Loss:
    """A loss test that ends the loss for a score above 0.5 and counts its frames unseen."""

    def __init__(self):
        self.lost, self.unseen, self.acquired, self.llr = True, 0, [], 0.0

    def would_acquire(self, s, lp=0.0):
        return float(s[0]) > 0.5, float(s[0])

    def acquire(self, s, lp=0.0):
        self.unseen += 1
        self.llr = float(s[0])
        self.acquired.append(float(s[0]))
        if float(s[0]) > 0.5:
            self.lost = False
            return True
        return False

    def unseen_frame(self):
        self.unseen += 1


class _Host(VetoMixin):
    """Three candidates 100 px apart; the ones at ``refused`` x positions are vetoed."""

    def __init__(self, retries, refused, scores=(0.9, 0.8, 0.3), *, width=320, acquire_in_frame=0.0,
                 acquire_unique=False, hold=0, margin=0.0, early_frames=0, exit_strip=None, searching_for=0,
                 sliver_frames=0, sliver_llr=0.0):
        self.params = SimpleNamespace(search_retries=retries, acquire_samples=3, kickoff_fraction=0.1,
                                      n_particles=30, acquire_in_frame=acquire_in_frame,
                                      acquire_early_frames=early_frames, acquire_in_frame_early=0.25,
                                      acquire_unique=acquire_unique, acquire_unique_hold=hold,
                                      acquire_unique_refine=False, acquire_unique_margin=margin,
                                      acquire_sliver_frames=sliver_frames, acquire_sliver_llr=sliver_llr)
        self.frame_index, self._ambiguous_until = searching_for, -1
        self._sliver = None
        self._search_since = 0
        self._strip = exit_strip
        self._shape = (120, width)
        self.loss = _Loss()
        self.size = (10.0, 10.0)
        self.refused = set(refused)
        self.asked = []
        xs = np.repeat([50.0, 150.0, 250.0], 10)
        self.states = np.zeros((30, 7))
        self.states[:, 0] = xs
        self.states[:, 1] = 60.0
        self.states[:, 4:6] = 10.0
        self.score = dict(zip((50.0, 150.0, 250.0), scores))

    def _exit_strip(self):
        return self._strip

    def _vetoed_by(self, frame, ell, llr=float("inf")):
        self.asked.append(float(ell[0]))
        return "leaving" if float(ell[0]) in self.refused else None

    def _skip_scene(self, frame, ell, rank, best, scores):
        return best, scores(best)

    def candidates(self):
        ell = self.states[:, [0, 1, 4, 5]]
        rank = np.array([self.score[x] for x in self.states[:, 0]]) + np.linspace(0, 1e-3, 30)
        best = int(np.argmax(rank))

        def scores(i):
            return np.array([self.score[float(self.states[i, 0])]]), 0.0
        s, lp = scores(best)
        near = near_mask(self.states, self.states[best, :2], self.size)
        return SearchCandidates(self.states, ell, None, None, None, None, best, lp, near, s, 0, rank, scores)


def _choose(host):
    return host._choose(None, host.candidates(), np.ones(30, bool))


def test_the_best_candidate_is_taken_when_no_veto_refuses_it():
    host = _Host(2, refused=())
    a = _choose(host)
    assert a.found and not a.vetoed and not a.vetoes and host.states[a.best, 0] == 50.0
    assert a.cluster.sum() == 10 and host.loss.unseen == 1 and host.asked == [50.0]


def test_a_refused_candidate_gives_way_to_the_next():
    host = _Host(2, refused=(50.0,))
    a = _choose(host)
    assert a.found and a.vetoed and host.states[a.best, 0] == 150.0 and a.vetoes == ("leaving",)
    assert set(host.states[a.cluster, 0]) == {150.0}
    assert host.loss.unseen == 1 and host.loss.acquired == [0.8]  # the loss test moved one frame


def test_without_retries_the_refusal_ends_the_frame():
    host = _Host(0, refused=(50.0,))
    a = _choose(host)
    assert not a.found and a.vetoed and host.states[a.best, 0] == 50.0
    assert host.loss.lost and host.loss.unseen == 1  # acquire() ended the loss, the veto restored it
    assert host.asked == [50.0]


def test_a_candidate_that_would_not_end_the_loss_is_not_asked():
    host = _Host(2, refused=(50.0,), scores=(0.9, 0.3, 0.2))
    a = _choose(host)
    assert not a.found and a.vetoed and host.states[a.best, 0] == 50.0  # the first is reported
    assert host.asked == [50.0] and host.loss.lost and host.loss.unseen == 1


def test_retries_are_bounded():
    host = _Host(1, refused=(50.0, 150.0), scores=(0.9, 0.8, 0.7))
    a = _choose(host)
    assert not a.found and host.asked == [50.0, 150.0]
    host = _Host(2, refused=(50.0, 150.0), scores=(0.9, 0.8, 0.7))
    a = _choose(host)
    assert a.found and host.states[a.best, 0] == 250.0 and a.vetoes == ("leaving", "leaving")


@pytest.mark.parametrize("width, found", [(255, True), (248, False)])
def test_a_best_candidate_mostly_outside_the_frame_ends_the_choice(width, found):
    """acquire_in_frame = 0.5: the best candidate's box (x 240-260) is 75 % inside a frame 255 px wide and is
    taken; 40 % inside one 248 px wide, nothing is acquired on this frame and the next best is not asked."""
    host = _Host(2, refused=(), scores=(0.3, 0.8, 0.9), width=width, acquire_in_frame=0.5)
    a = _choose(host)
    assert a.found == found and host.states[a.best, 0] == 250.0
    assert host.asked == ([250.0] if found else [])
    assert host.loss.unseen == 1 and host.loss.lost != found  # the loss test moved one frame either way


@pytest.mark.parametrize("searching_for, strip, found", [(5, (1, 40.0), True), (15, (1, 40.0), False),
                                                       (5, None, False)])
def test_right_after_an_exit_a_candidate_needs_less_of_its_box_inside(searching_for, strip, found):
    """acquire_early_frames = 10: the best candidate's box is 40 % inside (a frame 248 px wide); 5 frames into a
    search after an exit it is taken at the lower bar (0.25), 15 frames in it is not, nor after a loss that was
    not an exit."""
    host = _Host(2, refused=(), scores=(0.3, 0.8, 0.9), width=248, acquire_in_frame=0.5, early_frames=10,
                 exit_strip=strip, searching_for=searching_for)
    a = _choose(host)
    assert a.found == found and host.states[a.best, 0] == 250.0


def test_a_sliver_found_on_k_search_frames_in_a_row_is_taken():
    """acquire_sliver_frames = 3: the best candidate's box is 40 % inside (a frame 248 px wide) and passes the loss
    test on every frame. It is refused on the first two search frames and taken on the third; a gap of three
    frames, a candidate elsewhere, or a new search starts the count again; 0 never takes it."""
    def frames(host, indices, moves=None):
        found = []
        for i in indices:
            host.frame_index = i
            host.loss.lost = True
            if moves and i in moves:
                host.states[20:, 1] = moves[i]
            found.append(_choose(host).found)
        return found

    def host(k=3):  # the best candidate 40 % inside a frame 248 px wide
        return _Host(2, (), (0.3, 0.8, 0.9), width=248, acquire_in_frame=0.5, sliver_frames=k)

    assert frames(host(), [10, 11, 12]) == [False, False, True]
    assert frames(host(), [10, 12, 14]) == [False, False, True]  # searches every other frame
    assert frames(host(), [10, 11, 14, 15, 16]) == [False, False, False, False, True]
    assert frames(host(), [10, 11, 12, 13], moves={12: 20.0, 13: 20.0}) == [False, False, False, False]
    h = host()
    assert frames(h, [10, 11]) == [False, False]
    h._search_since = 12  # lost again: a new search
    assert frames(h, [12, 13, 14]) == [False, False, True]
    assert frames(host(0), range(10, 20)) == [False] * 10


@pytest.mark.parametrize("sliver_llr, found", [(0.0, False), (0.85, True), (0.9, True), (0.95, False)])
def test_a_sliver_with_an_unambiguous_ratio_is_taken(sliver_llr, found):
    """acquire_sliver_llr: the best candidate's box is 40 % inside (a frame 248 px wide) and passes the loss test
    with a ratio of 0.9 (this stub's ratio is the score). It is taken on the first search frame when the option asks
    at most that ratio, refused when it asks more, and refused with the option off; the frame's loss test moves
    once either way."""
    host = _Host(2, refused=(), scores=(0.3, 0.8, 0.9), width=248, acquire_in_frame=0.5, sliver_llr=sliver_llr)
    a = _choose(host)
    assert a.found == found and host.states[a.best, 0] == 250.0
    assert host.asked == ([250.0] if found else []) and host.loss.unseen == 1 and host.loss.lost == (not found)


def test_a_candidate_with_a_passing_rival_elsewhere_is_not_taken():
    """acquire_unique: the best (x = 50) would end the loss, and so would the candidate at x = 150: nothing is
    taken on this frame, the rival is not taken either, and the loss test moves one frame on the first."""
    host = _Host(2, refused=(), scores=(0.9, 0.8, 0.3), acquire_unique=True)
    a = _choose(host)
    assert not a.found and a.vetoed and a.vetoes == ("unique",) and host.states[a.best, 0] == 50.0
    assert host.asked == [] and host.loss.lost and host.loss.unseen == 1 and host.loss.acquired == [0.9]


def test_a_candidate_that_stands_alone_is_taken():
    """acquire_unique: the samples near the best pass too (they are the same object), the others do not."""
    host = _Host(2, refused=(), scores=(0.9, 0.3, 0.2), acquire_unique=True)
    a = _choose(host)
    assert a.found and not a.vetoed and host.states[a.best, 0] == 50.0 and host.asked == [50.0]


@pytest.mark.parametrize("margin, found", [(0.0, False), (0.2, False), (0.05, True)])
def test_a_rival_counts_within_the_margin_of_the_candidates_ratio(margin, found):
    """acquire_unique_margin: the candidate's ratio is 0.9 and the rival's 0.8 (both pass). Any passing rival counts
    with 0; with a margin of 0.2 the rival is close enough; with 0.05 it is not, and the candidate is taken."""
    host = _Host(2, refused=(), scores=(0.9, 0.8, 0.3), acquire_unique=True, margin=margin)
    a = _choose(host)
    assert a.found == found and host.states[a.best, 0] == 50.0


@pytest.mark.parametrize("hold, found", [(0, True), (2, False)])
def test_a_hold_after_two_look_alikes_refuses_the_next_frames(hold, found):
    """acquire_unique_hold: two frames after a frame with a rival, a candidate standing alone is still refused
    with a hold of 2 (none asked, the loss test moves one frame), and taken without one."""
    host = _Host(2, refused=(), scores=(0.9, 0.8, 0.3), acquire_unique=True, hold=hold)
    assert not _choose(host).found
    host.frame_index = 2
    host.score = {50.0: 0.9, 150.0: 0.3, 250.0: 0.2}
    host.asked, host.loss.unseen = [], 0
    a = _choose(host)
    assert a.found == found and a.vetoed != found and host.loss.unseen == 1
    assert host.asked == ([50.0] if found else [])
    host.frame_index = 3  # the hold is over
    assert _choose(host).found


@pytest.mark.parametrize("name", ["color-pf", "fusion-pf"])
def test_the_trackers_default_to_two_retries(name):
    assert pftrack.create_tracker(name).params.search_retries == 2
    assert pftrack.create_tracker(name, search_retries=0).params.search_retries == 0


def _twins_after_a_vanish(seed: int):
    """The target vanishes at frame 30; two twins walk up and down at either side of the view."""
    from pftrack.synth import Scene
    from pftrack.synth.scenes import SceneSpec, Target

    target = Target(path=((0, 160.0, 120.0), (30, 200.0, 120.0)), size=(26.0, 52.0), disappear=30)
    twins = (Target(path=((0, 50.0, 60.0), (70, 50.0, 190.0)), size=(26.0, 52.0)),
             Target(path=((0, 280.0, 190.0), (70, 280.0, 60.0)), size=(26.0, 52.0)))
    scene = Scene(SceneSpec(n_frames=70, seed=seed, targets=(target, *twins), background="flat", kind="vanish"))
    return scene.frames(), scene.groundtruth()


@pytest.mark.parametrize("seed", [0, 1])
def test_a_rival_reached_off_its_centre_is_found_by_the_refined_look(seed):
    """acquire_unique_refine: after the target vanishes, the search's best candidate is one twin and its samples
    reach the other only off its centre, where it fails the test. Scored again on the grid around that sample, the
    other twin passes too, and neither is taken: the flag stays up. Without the refined look a twin is taken."""
    frames, truth = _twins_after_a_vanish(seed)
    up = {}
    for refine in (False, True):
        t = pftrack.create_tracker("fusion-pf", seed=seed, acquire_unique_refine=refine)
        t.init(frames[0], tuple(truth[0]))
        lost = [t.update(f).lost for f in frames[1:]]
        up[refine] = float(np.mean(lost[30:]))
    assert up[False] < 0.2 and up[True] > 0.9
