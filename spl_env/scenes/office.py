"""OFFICE: seed 001's indoor scene (§5.1 Fig. 5.2, results §5.4.7.1), a room with five columns
and a plant.

The seed's figures are missing; this layout is ours, built to hold the corner cases the seed
names: "the plant is really close to the wall which difficulties the estimation of
breakpoints", "two small columns close to each other", and a big column whose arc a
classifier takes for lines (its Fig. 5.21, left). A 10 m x 8 m room (inner faces at
x = ±5 m, y = ±4 m), walls 2.5 m high; all objects are perfect cylinders (seed: "the column
models are primitive shapes based on cylinders"). Centres in m, field frame; gap = free space
to the nearest wall or, for the pair, between the two surfaces.

==========  ======  ============  =====  ======  ===================================================
object      kind    centre x, y   R      height  corner case
==========  ======  ============  =====  ======  ===================================================
column_1    column  -2.30,  0.30  0.55   2.5     wide column, 0.75 m from the west leg: a 0.3 m
                                                 piece of its arc bows only 2 cm from its chord,
                                                 the laser's noise, so pieces read as lines
column_2    column   2.90,  1.10  0.12   2.5     small pair with column_3, surfaces 0.20 m apart:
column_3    column   2.90,  0.63  0.15   2.5     side by side from the east leg, their segments
                                                 nearly touch in bearing; from the south and north
                                                 legs one hides part of the other
column_4    column   0.30, -1.30  0.20   2.5     a plain, free-standing column in the open: the
                                                 easy reference case
column_5    column  -4.40,  1.20  0.30   2.5     0.30 m from the west wall: wall and column split
                                                 by a clear range jump, the contrast to the plant
plant       plant    2.40,  3.72  0.20   0.6     pot 0.08 m from the north wall: from the route the
                                                 pot's edge and the wall behind it differ by little
                                                 range, so breakpoints between them are hard
==========  ======  ============  =====  ======  ===================================================

Route: a counter-clockwise rectangle, lap 25.6 m (about 51 s at 0.5 m/s, so a 60 s episode
drives one lap and a bit), start at (-3.6, -2.6) heading +x towards the first waypoint:

=========  ===========  ====================================================================
waypoint   x, y (m)     why
=========  ===========  ====================================================================
0          3.6, -2.6    south leg: passes column_4 and sees the pair end-on (one behind the
                        other)
1          3.6,  3.0    east leg: 0.55 m beside the pair, which it sees side by side
2         -3.6,  3.0    north leg: 0.52 m from the plant, 1.0 m from the north wall, so the
                        pot is seen against the wall just behind it
3         -3.6, -2.6    west leg: 0.75 m from the wide column and 0.50 m from column_5
=========  ===========  ====================================================================

The four interior columns lie inside the loop and are seen from all round within a lap;
column_5 and the plant, between the route and a wall, from the half facing the room.
"""

from __future__ import annotations

from spl_env.scenes.rooms import RoomLayout, SceneObject

COLUMN_RGBA = (0.80, 0.80, 0.78, 1.0)
POT_RGBA = (0.70, 0.36, 0.22, 1.0)
COLUMN_HEIGHT_M = 2.5  # floor to ceiling
POT_HEIGHT_M = 0.6


def _column(name: str, x: float, y: float, radius: float) -> SceneObject:
    return SceneObject(
        name=name,
        kind="column",
        x_m=x,
        y_m=y,
        radius_m=radius,
        height_m=COLUMN_HEIGHT_M,
        rgba=COLUMN_RGBA,
    )


OFFICE = RoomLayout(
    name="office",
    half_size_m=(5.0, 4.0),
    wall_height_m=2.5,
    wall_thickness_m=0.1,
    objects=(
        _column("column_1", -2.30, 0.30, 0.55),
        _column("column_2", 2.90, 1.10, 0.12),
        _column("column_3", 2.90, 0.63, 0.15),
        _column("column_4", 0.30, -1.30, 0.20),
        _column("column_5", -4.40, 1.20, 0.30),
        SceneObject(
            name="plant",
            kind="plant",
            x_m=2.40,
            y_m=3.72,
            radius_m=0.20,
            height_m=POT_HEIGHT_M,
            rgba=POT_RGBA,
        ),
    ),
    waypoints=((3.6, -2.6), (3.6, 3.0), (-3.6, 3.0), (-3.6, -2.6)),
    start_pose=(-3.6, -2.6, 0.0),
)
