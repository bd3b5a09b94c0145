import numpy as np

from slax_drake.perception.segmentation import grow_by_depth


def test_edge_pixels_join_the_neighbour_they_continue_in_depth_not_the_higher_label():
    """A near object (label 1, 0.60 m) seen from above: its top face recedes 3 cm per row (all edge pixels) toward
    a far object (label 2, 0.95 m) above it in the image. The top face must grow from label 1."""
    depth = np.full((12, 6), 0.95)
    depth[6:] = 0.60
    depth[3:6] = [[0.69], [0.66], [0.63]]  # rows 3..5: the top face, 3 cm per row
    labels = np.zeros(depth.shape, np.int32)
    labels[:2] = 2
    labels[7:] = 1
    grow = np.ones(depth.shape, bool)
    grown = grow_by_depth(labels, grow, depth, np.full(depth.shape, 0.012))
    assert (grown[3:7] == 1).all()
    assert (grown[2] == 2).all()  # 0.95 m: continues the far object
    assert (grown[:2] == 2).all() and (grown[7:] == 1).all()  # labelled pixels keep their label


def test_only_the_pixels_allowed_to_grow_change_and_an_isolated_one_stays_unassigned():
    depth = np.full((5, 5), 0.8)
    labels = np.zeros((5, 5), np.int32)
    labels[0, 0] = 3
    grow = np.zeros((5, 5), bool)
    grow[0, 1] = grow[4, 4] = True
    grow[4, 4] = True
    grown = grow_by_depth(labels, grow, depth, np.full(depth.shape, 0.01))
    assert grown[0, 1] == 3
    assert grown[4, 4] == 0  # no labelled pixel reaches it through growable pixels
    assert np.count_nonzero(grown) == 2
