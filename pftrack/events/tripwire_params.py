"""The parameters of the trackerless tripwire (:class:`~pftrack.events.tripwire.TrackerlessTripwire`, book
ch. 10): the chapter's, with their source lines, and pftrack's additions, each with the data it was chosen on."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from ..cues.foreground import DARK_NOISE_LIMIT, GREY_SHADOW_THRESHOLD
from ..params import Params, param

__all__ = ["TripwireParams"]


@dataclass(frozen=True, kw_only=True)
class TripwireParams(Params):
    """Options of the trackerless tripwire (ch10.md §2; the text gives no values for any of them)."""

    radius: float = param(12.0, gt=0, doc="patch radius r = envelope half-width in pixels (Eq. 1)")
    spacing: float | None = param(None, doc="arc-length spacing of the patches (default r: 50 % overlap)")
    direction: Literal["positive", "negative", "both"] = param("both", doc="crossings to detect")
    bgs: Literal["mog2", "mog", "diff"] = param("mog2", doc=(
        "foreground: MOG2 (shadows as background), MOG (OpenCV contrib's Gaussian mixture without a shadow test; "
        "bgs_history, bgs_mog_ratio; the band options apply to it too) or 3-frame difference"))
    bgs_mog_ratio: float = param(0.7, gt=0, le=1, doc=(
        "with bgs = 'mog': the share of the mixture's weight that is background (OpenCV's default; "
        "docs/rules/tripwire_bgs_mog_rule.txt)"))
    bgs_history: int = param(500, ge=2, doc="MOG2 history in frames")
    bgs_rate_k: float = param(2.0, gt=0, doc=(
        "MOG2 learns at 1 / min(k n, bgs_history) on its n-th frame; 2 is OpenCV's own schedule, a larger k a slower "
        "start (slow walkers stay foreground longer in the first bgs_history / k frames). An option: 4 found 80 of the "
        "PETS tune frames' 96 crossings against 74, at mean F1 0.824 against 0.815, short of its rule "
        "(docs/rules/tripwire_bgs_rate_rule.txt)"))
    bgs_threshold: float = param(16.0, gt=0, doc="MOG2 varThreshold")
    bgs_grey_shadow_threshold: float = param(GREY_SHADOW_THRESHOLD, ge=0, le=1, doc=(
        "MOG2's shadow threshold on grey frames, where its shadow test cannot tell a shadow from an object up to "
        "twice as dark as the ground: a darker pixel is a shadow only above this fraction of the background's "
        "brightness (1: none; 0.5: OpenCV's, as on colour frames; 0.85 chosen on the grey tune data, "
        "docs/tripwire.md; pftrack.cues.foreground)"))
    bgs_band: bool = param(True, doc=(
        "MOG2 models only the rows and columns that hold pixels within the neighbourhood's reach of the wire (the "
        "patches' radius plus the block matching's range and margins), not the whole bounding box of an oblique "
        "wire; inside them every pixel's label is the one the whole box gives (MOG2 models each pixel on its own), "
        "outside them nothing is foreground, so a blob that reaches beyond them is cut there. A wire across the view "
        "diagonally then costs a fraction of its box: PETS at 7 fps, 70 -> 100 fps; the same events on the PETS "
        "and traffic families, one crossing fewer of the tune walkers' 69 (docs/tripwire.md, Speed)"))
    bgs_reach: float = param(0.0, ge=0, doc=(
        "with bgs_band, MOG2 models the pixels within min(full reach, bgs_reach * r) of the wire (0: the full reach, "
        "the patches' radius plus the block matching's range and margins). The foreground is read on the patches' "
        "discs and blocks (within 2 r) and by the blobs of the foot timing, which reach about an object's height "
        "from the wire; the block matching's range only needs the grey frames. An option: 8 ran 1.28x as fast on "
        "the PETS tune frames at mean F1 0.820 against 0.815 but lost one crossing at stride 3, failing its rule "
        "(docs/rules/tripwire_bgs_reach_rule.txt)"))
    bgs_scale: int = param(1, ge=1, le=4, doc=(
        "MOG2 models the neighbourhood reduced by this factor (block means), its mask brought back to full size "
        "by nearest neighbour, as pftrack mot's detector does. An option: 2 ran 1.86x as fast on the PETS tune "
        "frames but lost F1 on four of the six tune families (mean 0.798 against 0.815), failing its rule "
        "(docs/rules/tripwire_bgs_scale_rule.txt)"))
    bgs_outer_scale: int = param(4, ge=1, le=4, doc=(
        "MOG2 models the band beyond bgs_near * r of the wire reduced by this factor (block means of the band's "
        "blocks, its mask brought back by nearest neighbour), and the pixels within bgs_near * r at full size, each "
        "with a model of its own (1: the whole band at full size). The patches' discs and blocks (within 2 r) keep "
        "their labels; the blobs of the foot timing, which reach farther, see a coarser mask there. 2 with "
        "bgs_near 5, chosen under docs/rules/tripwire_outer_scale_rule.txt: 1.21x as fast on the PETS tune frames "
        "(median of six lines), mean F1 over the six tune families 0.812 against 0.815 (PETS stride 3: one more "
        "false event; the walkers: one more), dark tune half 0.755 against 0.742, casts 0.817 against 0.831; "
        "bgs_near 3 lost crossings of the walkers. Then 4, under docs/rules/tripwire_outer_scale_34_rule.txt: 1.10x "
        "as fast as 2, mean F1 0.814 against 0.812, dark 0.753 against 0.755, casts 0.820 against 0.817 (3: 1.02x, "
        "too little). Not with faithful"))
    bgs_near: float = param(5.0, gt=0, doc=(
        "with bgs_outer_scale > 1, the reach of the full-size model, in patch radii r"))
    bgs_bootstrap: float = param(0.0, ge=0, doc=(
        "seconds of processed frames (at least 3) held at the start; MOG2 learns them with their moving pixels "
        "replaced by the per-pixel median (pftrack.cues.foreground.still_frames), then they are processed (0: off; "
        "MOG2 alone takes the first frames' objects for background). An option: 4 s found 80 of the PETS tune "
        "frames' 96 crossings at strides 1-3 against 74, at mean F1 0.825 against 0.817, short of its rule"))
    dark_stretch: float = param(2.5, ge=0, le=8, doc=(
        "a dark camera: when the first frame's bright end (its 99.5th percentile, pftrack.cues.quantize.level_gain) "
        "needs a gain of at least this to reach level 255, the wire's neighbourhood is multiplied by that gain (at "
        "most 8) on every frame before anything else, as pftrack mot's detector does (MOG2's floor on a pixel's "
        "variance and the 8 x 8 x 8 colour bins are made for the full range); 0: never. 2.5 with dark_denoise "
        "8.66, chosen under docs/rules/tripwire_dark_rule2.txt (docs/tripwire.md): three dark cameras of the PETS "
        "tune half never run before, F1 0.776 against 0.584 over strides 1-3; the six tune families and 20 fresh "
        "walker scenes identical (2 failed the first rule: mid-grey synthetic scenes were stretched)"))
    dark_denoise: float = param(DARK_NOISE_LIMIT, ge=0, le=255, doc=(
        "under dark_stretch: when the first frame's noise (pftrack.cues.foreground.noise_sigma) times the gain "
        "exceeds this many grey levels, the neighbourhood is smoothed by a 3 x 3 Gaussian before the stretch; 0: "
        "never. 8.66 = sqrt(75), the spread of MOG2's variance ceiling, as pftrack mot's default"))
    cast_jump: float = param(0.2, ge=0, le=3, doc=(
        "a white balance that jumps: a frame whose chromatic jump against the previous processed frame (the largest "
        "minus the smallest of the channels' median log-ratios over the whole frame, pftrack.cues.still_gain."
        "CastUndo) is at least this multiplies a per-channel gain by the jump's, and the wire's neighbourhood is "
        "divided by that gain before the background subtraction and the patches' histograms; 0: never. 0.2, as "
        "pftrack mot's, chosen under docs/rules/tripwire_cast_jump_rule.txt (docs/tripwire.md): the PETS tune half "
        "with casts of 0.15 and 0.25, F1 0.831 against 0.601 over strides 1-3; the six tune families identical"))
    light_jump: float = param(0.18, ge=0, le=3, doc=(
        "lamps switched on or off: a frame whose channels' median log-ratios against the previous processed frame are "
        "at least this on average, in size (every channel at once), takes that jump into cast_jump's gain; 0: never. "
        "0.18, chosen under docs/rules/light_jump_rule.txt (docs/tripwire.md): the PETS tune half with its light "
        "times 1.25, 1.5 and 0.7, F1 0.815 against 0.709 over strides 1-3; the six tune families identical"))
    light_jump_grey: bool = param(True, doc=(
        "light_jump between grey frames too (a grey camera's lamps); a switch between a colour and a grey frame "
        "reads no jump either way. Chosen under docs/rules/grey_light_tripwire_rule.txt (docs/tripwire.md): the grey "
        "PETS tune half with its light times 1.2, 1.4 and 0.6, F1 0.668 against 0.603 over strides 1-3; the grey "
        "and colour tune halves as recorded identical"))
    clip_fill: bool = param(False, doc=(
        "once a jump is undone, a level clipped at 255 in a brightened channel takes the level seen there just "
        "before the jump when that is higher (pftrack.cues.still_gain.CastUndo). An option: under "
        "docs/rules/clip_fill_rule.txt seven tune copies gave F1 0.765 against 0.757 over strides 1-3, short of the "
        "0.03 asked (pftrack mot took it)"))
    diff_threshold: int = param(25, ge=1, le=255, doc="grey-level threshold of the frame difference")
    fg_ratio: float = param(0.3, gt=0, le=1, doc="foreground fraction of a disc that makes the patch foreground")
    contact: Literal["any", "bottom"] = param("any", doc=(
        "any: the text's reading, a patch is foreground when enough of its disc is; bottom: only where an "
        "object's lower edge is (the disc moved down by 1.5 r is mostly background), so that an upright object "
        "crosses when its foot point does (a walker's head crosses the image of a horizontal wire long before "
        "the walker does); on the PETS tune frames it traded recall for precision"))
    bits: int = param(2, ge=1, le=8, doc=(
        "bits per RGB channel of the patch histograms (2: 4x4x4 = 64 bins; the text gives no bin count, L9196). A "
        "disc of r = 10 px holds a few hundred foreground pixels, too few to fill 512 bins: the same walker's "
        "colours seen on the two sides scored S_c 0.6-0.74. 2 chosen with threshold 0.8 and t_max 4 on the tune "
        "data (PETS frames 1-200 at strides 1-3: 57 of 96 crossings found against 50 with 3 bits, 0.75 and 3 s; "
        "docs/tripwire.md)"))
    hist_pixels: Literal["fg", "all"] = param("fg", doc="histogram of the disc's foreground pixels, or of all of them")
    novelty: float = param(0.3, gt=0, le=1, doc="D_B to the last entry above which a new entry is appended")
    alpha_c: float = param(0.7, ge=0, doc="weight of the colour similarity (alpha_c > alpha_m, L9309)")
    alpha_m: float = param(0.3, ge=0, doc="weight of the motion consistency")
    threshold: float = param(0.8, doc="theta_S: a crossing when max S exceeds it (Eq. 7); 0.8 with 2 bits (0.75 "
                                      "was chosen with 3 bits)")
    t_th: float = param(0.1, ge=0, doc="T_th in seconds: an inner appearance must be at least this old")
    t_max: float = param(4.0, gt=0, doc="T_max in seconds: history entries last seen longer ago are ignored (4 "
                                       "chosen with bits; 3 before)")
    max_entries: int = param(32, ge=1, doc="history entries kept per patch")
    v_max: float = param(600.0, gt=0, doc=(
        "largest speed in px/s, for the SSD search range and the depth of the wire's neighbourhood (set for "
        "vehicles; pftrack tripwire --v-max auto reads it from the first 10 s, pftrack.events.blobs.estimate_speed: "
        "2.1x as fast on PETS at 7 fps but 6 fewer of the tune families' crossings, so not the default; "
        "docs/rules/tripwire_vmax_auto_rule.txt)"))
    motion_prior: float = param(1.0, ge=0, doc=(
        "lambda of the SSD block matching's prior for small motions: a displacement of d px per frame of the "
        "source costs lambda |d|^2 more per matched pixel (grey levels^2 per px^2; with --stride K, the K-frame "
        "displacement D costs lambda |D / K|^2; pftrack's addition, 0 = the text's plain SSD). A patch of a "
        "uniformly dark coat otherwise finds its best match on another dark patch 40-85 px away, and C_d rejects "
        "the crossing. 1 chosen on the PETS tune frames at strides 1-3, the synthetic walkers and the top-down "
        "traffic at strides 1-5 (tune seeds; docs/tripwire.md)"))
    colour: Literal["db", "bc"] = param("db", doc="S_c = 1 - D_B (restored) or the coefficient itself (ch10.md P1)")
    away_angle: float = param(60.0, gt=0, le=90, doc="C_d (Eq. 4) made strict: the motion must point within this "
                                                     "angle of straight away from the wire (90 is the text's "
                                                     "v.w < 0); walkers moving along the wire do not cross it")
    min_motion: float = param(0.5, ge=0, doc="C_d also needs at least this motion in px per processed frame (the "
                                             "direction of a smaller SSD motion is noise)")
    max_lateral: float = param(3.0, gt=0, doc="compare only patches of the other side within this many r of arc "
                                              "length (ch10.md P9; an object crosses, it does not jump along the "
                                              "wire)")
    fresh_time: float = param(1.0, ge=0, doc="a crossing brings an appearance new to its side: if a patch of the "
                                             "same side within max_lateral r saw a matching appearance (S above "
                                             "the threshold) in the last fresh_time seconds, the object was "
                                             "already there (walking along the wire, or counted); 0 turns it off")
    faithful: bool = param(False, doc="the text as written: no t_max, no consumption, no refractory, no grouping, "
                                      "timing 'match'")
    group: bool = param(True, doc="merge events of one object: an event where an emitted one of the same direction "
                                  "would be by now (its position moved by its motion, within 2r) in the last "
                                  "group_time seconds")
    group_time: float = param(2.0, gt=0, doc="how long an emitted event can absorb later ones, in seconds")
    group_blob: float = param(0.3, ge=0, doc=(
        "merge events of one object by its pixels: an event of the same direction emitted in the last group_blob "
        "seconds whose position (moved by its motion) lies in the same 8-connected foreground blob of the current "
        "frame as the new one; an upright walker's head and legs fire apart on a vertical wire (0: off). 0.3 s "
        "chosen on the PETS tune frames (precision 0.55 -> 0.60 at the same accuracy) and synthetic traffic seeds "
        "0-2 (unchanged but for one dense-traffic crossing of 300)"))
    timing: Literal["match", "foot", "centre"] = param("foot", doc=(
        "when a crossing happens (pftrack.events.timing; pftrack's addition): 'match' the text's, the frame where "
        "the appearance is matched on the far side (objects seen from above, the chapter's vehicles); 'foot' / "
        "'centre' the frame where that point of the object's box (its foreground blob, followed by overlap) "
        "passes the wire, as the tracker-based tripwire counts. A walker's head reaches the far side of a "
        "horizontal ground line long before its feet do. 'foot' (default) chosen on the PETS tune frames with "
        "`confirm`: accuracy 0.63 and precision 0.83 against 0.56 and 0.60 with 'match' (before motion_prior; "
        "0.66 / 0.84 against 0.59 / 0.63 with it); on top-down synthetic "
        "traffic (tune seeds 0-2) 'match' is better, because queued vehicles merge into one blob"))
    hold_time: float = param(6.0, gt=0, doc=(
        "with timing foot/centre: seconds an event may wait for its point to cross (a walker 100 px tall at 3 px "
        "per frame needs about 5 s at 7 fps); then, or when its blob is lost, it keeps its matching frame (or is "
        "dropped with confirm). 6 chosen on the PETS tune frames (2 and 4 lost one horizontal crossing)"))
    blob_close: float = param(1.0, ge=0, doc="with timing foot/centre: the foreground is closed with a square of "
                                             "this many r before its blobs are labelled (head, torso and legs of "
                                             "a walker in one blob)")
    confirm: bool = param(True, doc=(
        "with timing foot/centre: drop an event unless its point is seen to cross (on the origin side within the "
        "last `lookback` seconds or while held, then on the far side)"))
    crowd_width: float = param(0.0, ge=0, doc=(
        "with timing foot/centre: a blob wider than this many 2r (r is about half an object's width with --radius "
        "auto) is taken for several objects side by side, whose box point is nobody's: its events keep their "
        "matching frame, unconfirmed (0: off, the default). 2 helps in crowds (synthetic walkers, tune seeds: "
        "accuracy / precision 0.48 / 0.77 -> 0.64 / 0.70) but not on the PETS tune half (unchanged at stride 1, "
        "0.50 / 0.89 against 0.53 / 0.94 at stride 2, 0.22 / 0.41 against 0.28 / 1.00 at stride 3); the same "
        "trade with motion_prior (docs/tripwire.md)"))
    feet: bool = param(True, doc=(
        "with timing foot/centre: the blobs of the closed foreground near the wire are followed by overlap while "
        "they are seen, and a blob whose point crosses the wire (hysteresis foot_hysteresis px) is a crossing, "
        "unless a patch event already counted it (pftrack.events.blobs; pftrack's addition): a walker who "
        "reaches a ground line along it covers both sides before its feet cross, and the patches see nothing "
        "new arrive. Their events have to_patch = from_patch = -1 and no scores. On the PETS tune frames at "
        "strides 1-3: 74 of 96 crossings found at precision 0.82 / 0.96 / 0.91, against 57 at 0.88 / 1.00 / 0.94 "
        "without (docs/tripwire.md)"))
    foot_hysteresis: float = param(5.0, ge=0, doc="with feet: px the point must pass each side of the wire")
    foot_min_area: float = param(3.0, ge=0, doc="with feet: blobs of fewer than this many r^2 pixels are not "
                                                "followed (3 chosen on the tune data among 1, 2, 3, 4, 8)")
    foot_hold: int = param(0, ge=0, doc="with feet: processed frames a crossing waits before it is counted; it "
                                        "is dropped if the point goes back across the wire meanwhile (a blob's "
                                        "bottom jumps when MOG2 loses and finds the feet)")
    foot_inherit: Literal["wire", "always", "never"] = param("wire", doc=(
        "with feet: a blob that splits off a followed one (two walkers who overlapped part) starts on its "
        "parent's side when its point is on the wire, within the hysteresis ('wire'), whatever its point ('always'), "
        "or without a side ('never'). A walker who crossed while merged with another is then counted; but the "
        "side of a merged blob is that of its lowest foot, maybe another walker's. 'wire' chosen on the PETS tune "
        "frames (strides 1-3: 74 of 96 crossings at precision 0.82 / 0.96 / 0.91; 'always' 78 at 0.76 / 0.93 / "
        "0.82; 'never' 72 at 0.84 / 0.96 / 0.90) and the walkers of tune seeds 0-9 (38 of 69 at 0.78; 46 at 0.64; "
        "36 at 0.75)"))
    foot_window: float = param(6.0, gt=0, doc="with feet: seconds within which one blob's events of one direction "
                                              "are one event (6 chosen on the tune data among 1.5, 3, 6, 10)")
    merge_blob: bool = param(True, doc="with timing foot/centre: events of one direction on one blob are one event")
    lookback: float = param(2.5, ge=0, doc=(
        "with confirm: seconds the blob is followed backwards from the frame an event fires (the event is then "
        "dated by the frame its point reached the far side); MOG2 misses feet, which touch their shadows, so a "
        "walker's event often fires after its foot point has crossed. 2.5 s chosen on the PETS tune frames at "
        "strides 1-3 (stride 1, accuracy / precision: 0.53 / 0.89, 0.59 / 0.90, 0.59 / 0.86, 0.63 / 0.83 with "
        "0.7, 1.7, 2 and 2.5 s)"))
