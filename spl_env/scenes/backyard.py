"""BACKYARD: seed 001's outdoor scene (§5.1 Fig. 5.1, results §5.4.7.2), five trees in a
fenced yard.

The seed's figures are missing; this layout is ours. Its trees "do not draw a perfect circular
shape at the bottom of their trunks": the laser sees "a linear segment in one of its sides",
which worsens the circle estimate, most for the big trees 1 and 2 (its Table 5.2: radius
errors of 0.51 and 0.19 m). Each trunk here is a circle of radius R cut flat by a chord at
distance d from the centre, the chord's outward normal along the given direction; ground truth
is the round part's circle (x, y, R). The chord is ``2 sqrt(R² - d²)`` long. Trunk radii stay
within 0.15-0.45 m ("the size of trunks does not change much"). A 14 m x 12 m yard (inner faces
at x = ±7 m, y = ±6 m) inside a 1.2 m fence, so that the laser has returns all round; trunks
4 m high. Centres in m, field frame; directions in degrees (0 = +x = east, 90 = north).

======  ============  =====  =====  =====  =====  ==================================================
tree    centre x, y   R      d      chord  flat   corner case
                                                  faces
======  ============  =====  =====  =====  =====  ==================================================
tree_1  -2.50, -3.40  0.45   0.30   0.67   -90    big trunk, flat side square to the south leg
                                                  0.95 m away: a long straight piece in the arc
tree_2   4.60,  0.80  0.40   0.26   0.61     0    big trunk, flat side square to the east leg 0.80 m
                                                  away
tree_3  -4.90,  4.30  0.25   0.16   0.38    90    flat side towards the fence: the route sees only
                                                  its round part, the near-circular control
tree_4   4.80, -4.10  0.20   0.12   0.32   123    flat side square to the south-east diagonal leg,
                                                  so its scans alternate round and flat-faced views
tree_5  -0.60,  0.50  0.15   0.09   0.24   180    thinnest trunk, alone mid-yard, always 3.9 m or
                                                  more away: few beams per scan, flat side to the
                                                  west seen only from afar
======  ============  =====  =====  =====  =====  ==================================================

Route: a counter-clockwise hexagon, lap 38.5 m (about 77 s at 0.5 m/s: a 180 s episode drives
over two laps), start at (-5.8, -4.8) heading +x towards the first waypoint; 1.2 m from the
fence on its straight legs:

=========  ===========  ====================================================================
waypoint   x, y (m)     why
=========  ===========  ====================================================================
0           1.5, -4.8   south leg: past tree_1's flat side, then tree_4 from the west
1           5.8, -2.0   south-east diagonal: faces tree_4's flat side, cuts off its corner
2           5.8,  4.8   east leg: past tree_2's flat side
3          -1.5,  4.8   north leg: tree_5 and tree_2 across the yard
4          -5.8,  2.0   north-west diagonal: round tree_3 in its corner, flat side hidden
5          -5.8, -4.8   west leg: tree_5's flat side from afar, tree_1 from the west
=========  ===========  ====================================================================

tree_1, tree_2 and tree_5 lie inside the loop and are seen from all round within a lap;
tree_3 and tree_4, in the corners the diagonals cut off, from the half facing the yard.
"""

from __future__ import annotations

import math

from spl_env.scenes.rooms import RoomLayout, SceneObject

BARK_RGBA = (0.42, 0.30, 0.20, 1.0)
TRUNK_HEIGHT_M = 4.0


def _tree(
    name: str, x: float, y: float, radius: float, flat: float, facing_deg: float
) -> SceneObject:
    return SceneObject(
        name=name,
        kind="tree",
        x_m=x,
        y_m=y,
        radius_m=radius,
        height_m=TRUNK_HEIGHT_M,
        flat_side_m=flat,
        flat_side_direction_rad=math.radians(facing_deg),
        rgba=BARK_RGBA,
    )


BACKYARD = RoomLayout(
    name="backyard",
    half_size_m=(7.0, 6.0),
    wall_height_m=1.2,
    wall_thickness_m=0.1,
    objects=(
        _tree("tree_1", -2.50, -3.40, 0.45, 0.30, -90.0),
        _tree("tree_2", 4.60, 0.80, 0.40, 0.26, 0.0),
        _tree("tree_3", -4.90, 4.30, 0.25, 0.16, 90.0),
        _tree("tree_4", 4.80, -4.10, 0.20, 0.12, 123.0),
        _tree("tree_5", -0.60, 0.50, 0.15, 0.09, 180.0),
    ),
    waypoints=((1.5, -4.8), (5.8, -2.0), (5.8, 4.8), (-1.5, 4.8), (-5.8, 2.0), (-5.8, -4.8)),
    start_pose=(-5.8, -4.8, 0.0),
)
