# SPDX-License-Identifier: BSD-3-Clause
"""Folded faces of a tetrahedral mesh (numpy only): interior faces whose two tets lie on the same side
of the face, so the tets overlap although each has a positive volume. Shared by the data script and
the osteotomy strain diagnosis."""
import numpy as np

# Face k of a tet (VTK order) is the one opposite its local node k.
LOCAL_FACES = np.array([[1, 3, 2], [0, 2, 3], [0, 3, 1], [0, 1, 2]])


def face_pair_sides(xyz, tets):
    """Every interior face as a pair of (tet * 4 + local face) indices, and for each pair the product
    of the signed distances of the two opposite nodes from the face's plane (> 0: the same side)."""
    faces = tets[:, LOCAL_FACES].reshape(-1, 3)
    _, face_of, count = np.unique(np.sort(faces, axis=1), axis=0, return_inverse=True,
                                  return_counts=True)
    face_of = face_of.ravel()
    shared = np.where(count[face_of] == 2)[0]
    pairs = shared[np.argsort(face_of[shared], kind="stable")].reshape(-1, 2)
    f = xyz[faces[pairs[:, 0]]]
    normal = np.cross(f[:, 1] - f[:, 0], f[:, 2] - f[:, 0])
    opposite = tets.ravel()[pairs]
    side_a = np.einsum("ij,ij->i", normal, xyz[opposite[:, 0]] - f[:, 0])
    side_b = np.einsum("ij,ij->i", normal, xyz[opposite[:, 1]] - f[:, 0])
    return pairs, side_a * side_b
