"""Every random range of the crop generator, in one place (fractions unless said).

Changing a value here changes the training distribution: keep the ground truth exact
(tests/test_udir.py) and look at a contact sheet (`doctrpp crops` + `doctrpp sheet`).
"""

# -- pages (page.py) ---------------------------------------------------------------------
DOCUMENT_TYPES = {  # relative weights
    "article": 0.34,  # book and article pages, 1-3 columns, dense
    "magazine": 0.16,  # photos, colour boxes, big headings
    "letter": 0.12,
    "invoice": 0.12,
    "receipt": 0.08,
    "form": 0.10,
    "slide": 0.08,
}
PAGE_ASPECT = {  # long side / short side
    "article": (1.25, 1.5),
    "magazine": (1.25, 1.45),
    "letter": (1.29, 1.42),
    "invoice": (1.29, 1.42),
    "receipt": (2.0, 3.6),
    "form": (1.29, 1.42),
    "slide": (1.33, 1.78),
}
# Session 8: docunet_dev's pages carry denser, smaller text than ours did (edge density of
# 288 px crops 0.32 real against 0.21 ours): pitches moved down by about a fifth.
# Session 34 (`python -m doctrpp.udir.likeness`, 48 docunet_dev photos against 48 crops per
# kind): line pitch at 288 px 5.0 / 7.0 / 11.0 real against 4.5 / 7.0 / 17.0 ours (full
# page / partial / no-boundary); edge density 0.32 / 0.32 / 0.35 against 0.22 / 0.15 / 0.25.
# Text-heavier pages (article 0.44, magazine 0.14, invoice 0.10, form 0.08, slide 0.04),
# pitches x0.85 (not slides) and no-boundary crops of 0.35-0.8 closed the pitch gap (12.0 px
# on no-boundary crops) and trained one cycle that ended level on real photos and behind in
# unmasked MS-SSIM: not kept (docs/training_history.md, "Session 34").
LINE_PITCH = {  # text line pitch / page long side
    "article": (1 / 95, 1 / 45),
    "magazine": (1 / 95, 1 / 45),
    "letter": (1 / 75, 1 / 40),
    "invoice": (1 / 85, 1 / 42),
    "receipt": (1 / 80, 1 / 44),
    "form": (1 / 72, 1 / 38),
    "slide": (1 / 28, 1 / 16),
}
FONT_FAMILIES = {"times": 0.3, "serif": 0.2, "sans": 0.38, "mono": 0.12}  # typeset.FAMILIES
LANDSCAPE_SHARE = 0.12  # of pages other than slides and receipts
MARGIN = (0.04, 0.12)  # page margin / page side
PAGE_LONG_SIDE = 1024  # px of the flat page texture

# -- page geometry and camera (surface.py) -----------------------------------------------------
# Lengths in page heights; bends keep the paper's length (text foreshortens where it turns).
# Session 5: real photos (docunet_dev) show more folding and crumpling than session 4's
# crops did (a sheet side by side): folds are more frequent and steeper, and crumpled pages
# get many small creases, not only smooth bumps.
# Session 35 (`likeness`, 48 photos against 48 crops per kind): text-line coherence of the
# untouched, deskewed crops 0.575 / 0.653 / 0.718 real against 0.535 / 0.693 / 0.609 ours
# (complete / partial / no-boundary; lower = curlier): our pages bend as much as the real
# ones or more, so the ranges below stayed.
SURFACE_STYLES = {  # relative weights
    "perspective": 0.05,
    "curl": 0.17,
    "cone": 0.1,
    "fold": 0.2,
    "lift": 0.12,
    "crumple": 0.16,
    "combined": 0.2,
}
CURL_AMPLITUDE = (0.08, 0.35)  # sine part of a curl (session 7: was 0.05-0.25)
CURL_FREQUENCY = (1.5, 5.0)  # radians per page height
CURL_BOW = 0.7  # |quadratic part| of a curl (a cylinder-like bow; session 7: was 0.45)
CONE = 1.2  # |growth| of a curl along its axis
FOLDS_MAX = 4
FOLD_OFFSET = 0.35  # |crease distance| from the page centre
FOLD_SLOPE = 1.2  # |height gained per unit distance| from the crease (session 7: was 0.8)
FOLD_ALONG_AXES = 0.6  # share of folds parallel to a page side (folded in halves, quarters)
FOLD_SHARPNESS = (0.008, 0.04)  # width of the crease's rounding
LIFT_IN_COMBINED = 0.35  # share of combined surfaces that also lift an edge or corner
LIFT_START = (0.2, 0.8)  # where the lift starts / centre-to-edge distance
LIFT_EDGE_SLOPE = (0.6, 2.0)  # slope reached at the page edge (session 7: was 0.4-1.5)
LIFT_TOWARDS_CAMERA = 0.85
BUMPS = (3, 14)  # crumpling: number of bumps (upper bound exclusive)
BUMP_SIGMA = (0.06, 0.25)
BUMP_HEIGHT = 0.1  # normal sigma (session 7: was 0.06)
CREASES = (4, 14)  # crumpling: small creases at random angles (upper bound exclusive)
CREASE_SLOPE = (0.15, 0.6)  # |height gained per unit distance| from a small crease (s7: 0.1-0.4)
CREASE_OFFSET = 0.45  # |crease distance| from the page centre
CREASE_SHARPNESS = (0.01, 0.03)
# Session 42 (a sheet of crumple scenes beside docunet_dev 43_2 and 46_2): real crumpled
# paper shows many short creases meeting at odd angles, each a sharp line in the shading
# and a kink in the text lines; ours showed smooth waves (page-long creases and bumps,
# which only add height). Crumpled pages now also get local creases (surface.LocalCrease)
# that fade out along and across their line and pull the paper in as a fold does.
LOCAL_CREASES = (8, 26)  # per crumpled page (upper bound exclusive)
LOCAL_CREASE_LENGTH = (0.05, 0.22)  # window sigma along the line, page heights
LOCAL_CREASE_WIDTH = (0.5, 1.0)  # window sigma across the line / along it
LOCAL_CREASE_SLOPE = (0.15, 0.5)  # |height gained per unit distance| from the line
LOCAL_CREASE_SHARPNESS = (0.006, 0.02)
# Session 5 (a sheet of complete crops beside docunet_dev): people photograph a page held
# square to the phone, so most real pages are upright (roll within a few degrees), seen
# nearly from the front, and fill the frame; our crops showed rotated trapezoids filling
# half of it. Most cameras are now "aligned"; the rest keep the strong handheld angles.
# Session 7: the maps' bending (what is left after the best homography, map_shape.py) of
# session 6's complete crops was 1.8 px median at 288 px: text lines on them looked
# straight where docunet_dev's visibly wave. Two causes, both changed: the cameras stood
# 2.5-6 page heights away (a telephoto view, in which a page's height changes hardly move
# its image; a phone photographs a page from about its own height, with a wide lens), and
# the bends were gentle. Bending of complete crops: median 1.8 -> 2.7 px, q90 4.2 -> 7.1.
# Session 33 measured the gap that is left (the default's maps of the 96 docunet_dev photos,
# whole, against the true maps of generated complete crops; on generated crops the model
# reproduces these measures to a few per cent): real pages fill 0.83 of the frame (median;
# ours 0.69), their top and bottom edges turn 1.4 degrees (ours 3.1; q90 4.7 against 15.6)
# and opposite edges differ 1.08x in length (ours 1.21x); crumpled pages are the furthest
# off (4.8 degrees, 1.24x, 0.68 of the frame: many steep creases tilt the whole sheet).
# Ranges that close most of it (aligned share 0.85, aligned tilt 0.08, handheld tilt 0.25
# and roll 0.1, fold slope 0.8, crease slope 0.08-0.35, complete margin 0-0.035: 0.80 of
# the frame, 2.2 degrees, 1.13x) trained two cycles from the default that ended level on
# their own crops and behind on these, with fewer letters read on the real photos: not
# kept (docs/training_history.md, "Session 33"). Session 41 trained them again (1,100 steps)
# and judged the end on cross-shot agreement, the real-photo measure closest to the held-out
# check: level (-0.003 +- 0.004), and behind on generated crops.
ALIGNED_CAMERA_SHARE = 0.65
ALIGNED_TILT_SIGMA = 0.12  # radians
ALIGNED_ROLL_SIGMA = 0.04  # radians
ALIGNED_CAMERA_DISTANCE = (1.1, 2.2)  # page heights (session 7: was 2.5-6.0)
TILT_SIGMA = 0.3  # radians, camera tilt about x and y (handheld at an angle)
ROLL_SIGMA = 0.15  # radians, camera roll
CAMERA_DISTANCE = (1.1, 2.8)  # nearer = stronger perspective (session 7: was 1.6-5.0)
MIN_AREA_SCALE = 0.3  # redraw a surface whose image shrinks a page part below this (local
#                       area / median): folded over or nearly edge-on to the camera
# Session 41: 2% of scenes magnified some page part over 10x the median (a lift or crease
# reaching towards the camera plane; up to 1,000x), so the page's image ran far off and a
# "complete" crop framed a sliver of page in a large background (one such crop: 124 px map
# error against a 5.5 px mean). Median 1.7x, q90 3.5x.
MAX_AREA_SCALE = 10.0  # redraw a surface whose image magnifies a page part above this

# -- paper and print (paper.py) -------------------------------------------------------------
PAPER_WHITE_SHARE = 0.72  # the rest: cream/recycled (half) or light colours
PAPER_WHITE = (226, 252)  # grey level of white paper
PAPER_FIBRE_SIGMA = (0.8, 4.0)  # grey levels of fibre texture
SHOW_THROUGH = (0.0, 0.12)  # contrast of the other side's print (mirrored, blurred)
SHOW_THROUGH_SHARE = 0.4
INK_BLEED_SIGMA = (0.0, 0.7)  # px at PAGE_LONG_SIDE
PRINT_NOISE = (0.0, 0.25)  # relative ink density noise
# Light print on a dark or grey flood (covers, slides, posters): docunet_dev shows it in 4 of
# 96 photos (8_1, 8_2: white on black; 43_1, 43_2: white on grey).
REVERSED_PRINT_SHARE = 0.05
REVERSED_FLOOD = (8, 110)  # grey level of the flood colour
REVERSED_LETTERS = (190, 248)  # grey level of the lettering (the paper left unprinted)

# Pictures on pages (paper.photo). Session 35: the likeness sheet showed our pictures as
# saturated rainbow fields under heavy grain; docunet_dev's are products, people and rooms
# in muted colours on plain or lit backdrops, with sharp object edges.
PHOTO_SATURATION = (0.05, 0.55)  # HSV saturation of backdrop and objects
PHOTO_VALUE = (0.3, 0.95)  # HSV value (brightness)
PHOTO_ACCENT_SHARE = 0.25  # objects in one saturated colour (packaging, clothes)
PHOTO_OBJECTS = (2, 9)  # upper bound exclusive
PHOTO_LABEL_SHARE = 0.35  # objects carrying a label band with print on it
PHOTO_LIGHT = (0.1, 0.5)  # brightness change across the backdrop and each object
PHOTO_GROUND_SHARE = 0.5  # a floor, table or ground under the backdrop
PHOTO_GRAIN = (0.5, 5.0)  # grey levels of sensor / halftone grain
PHOTO_GREY_SHARE = 0.2  # black-and-white pictures (newsprint)

# -- framing (sample.py) ---------------------------------------------------------------------
# Session 8: docunet_dev's pages fill their frames (background on one or two sides, a few
# per cent); ours sat in twice as much background (a native-size sheet side by side).
COMPLETE_MARGIN = (0.0, 0.08)  # background per side / page bounding box side (s8: was 0-0.14)
NONE_CROP_SIZE = (0.3, 0.7)  # side / shorter page-bounding-box side
PARTIAL_CROP_SIZE = (0.4, 0.9)  # side / page bounding box side
# Session 34 (`python -m doctrpp.udir.likeness --sheet`): real partial crops are mostly page
# (ink share 0.13 against 0.05 ours); ours often show a small piece of page on a large
# background. 0.6-0.95 measures ink 0.084 and edge density 0.20 (0.15 here, 0.32 real);
# one short cycle on it (600 steps) ended level on real photos and behind on generated crops.
PARTIAL_PAGE_SHARE = (0.3, 0.9)  # of the crop covered by the page

# -- capture (effects.py) --------------------------------------------------------------------
# Lights and shadows are drawn over the photo's frame (the page's bounding box); a crop sees
# its own part of them (effects.apply_lighting). Strengths are the factor left in shadow.
GRADIENT_LOW = (0.7, 1.0)  # brightness factor at the dark end of a ramp across the frame
GRADIENT_HIGH = (1.0, 1.12)  # ... and at its bright end
CAST_SHADOW_SHARE = 0.35  # a straight-edged shadow (of a wall, a lamp arm) over part
CAST_SHADOW_STRENGTH = (0.45, 0.85)
CAST_SHADOW_SOFTNESS = (0.01, 0.12)  # edge width / frame side
HIGHLIGHT_SHARE = 0.2  # a glossy glare
HIGHLIGHT_RADIUS = (0.1, 0.5)  # / frame side
HIGHLIGHT_STRENGTH = (20, 80)  # grey levels added at its centre
HAND_SHADOW_SHARE = 0.25  # a soft shadow of a hand or phone
HAND_SHADOW_STRENGTH = (0.45, 0.8)
FINGERS_SHARE = 0.15  # fingers holding the page edge (complete and partial crops)
VIGNETTE = (0.0, 0.35)  # darkening at the corners
WHITE_BALANCE = (0.9, 1.08)  # per-channel gain
# Session 5: the real photos are mostly sharp with little noise; half our crops were
# blurred past legibility at 288 px. Session 8: still a quarter were (variance of the
# Laplacian of 288 px complete crops, lower quartile 212 ours against 1011 real; text lines,
# the cue to a page's bending, were gone on them): every blur rarer and milder.
BLUR_SHARE = 0.12  # defocus over the whole crop (session 8: was 0.25)
BLUR_SIGMA = (0.3, 0.8)  # px at 288 (session 8: was 0.3-1.0)
EDGE_DEFOCUS_SHARE = 0.15  # blur growing towards the crop edges (session 8: was 0.3)
EDGE_DEFOCUS_SIGMA = (0.5, 1.5)  # px at 288 at the corners (session 8: was 0.8-2.5)
MOTION_SHARE = 0.05  # (session 8: was 0.12)
MOTION_LENGTH = (1.5, 4.0)  # px at 288 (session 8: was 2-7)
JPEG_SHARE = 0.6
JPEG_QUALITY = (55, 96)  # (session 8: was 35-96)
NOISE_SIGMA = (0.5, 4.5)  # grey levels
LIGHT_OBLIQUE_SIGMA = 0.8  # sideways part of the light direction (1 = 45 degrees)
AMBIENT = (0.25, 0.8)  # light share that does not depend on the page's slope (shading)
