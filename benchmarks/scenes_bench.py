"""Benchmark scenes shared by the benchmark scripts."""

import exactff as ef

#: an 8 x 6 x 2.8 m room (z up) with 6 desks, 3 partitions and 2 bookshelves as boxes
OFFICE_BOXES = [
    ((1.0, 1.0, 0.0), (2.6, 1.8, 0.75)), ((3.2, 1.0, 0.0), (4.8, 1.8, 0.75)),
    ((5.4, 1.0, 0.0), (7.0, 1.8, 0.75)), ((1.0, 3.6, 0.0), (2.6, 4.4, 0.75)),
    ((3.2, 3.6, 0.0), (4.8, 4.4, 0.75)), ((5.4, 3.6, 0.0), (7.0, 4.4, 0.75)),
    ((1.0, 2.6, 0.0), (2.8, 2.65, 1.5)), ((3.1, 2.6, 0.0), (4.9, 2.65, 1.5)),
    ((5.2, 2.6, 0.0), (7.0, 2.65, 1.5)),
    ((0.5, 5.6, 0.0), (2.5, 6.0 - 1e-9, 2.0)), ((5.0, 5.6, 0.0), (7.0, 6.0 - 1e-9, 2.0)),
]


def furnished_room(k=26, box_k=2):
    """About 4,300 polygons for k = 26: 6 k^2 room quads plus 66 box_k^2 furniture quads."""
    return ef.scenes.furnished_box(k, OFFICE_BOXES, size=(8.0, 6.0, 2.8), box_k=box_k)
