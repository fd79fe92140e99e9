"""The floor: the floor model, segmentation refined by GrabCut, skirting boards, and the
floor polygon in meters."""
