# SPDX-License-Identifier: BSD-3-Clause
"""Per-cell strain of linear tetrahedra from nodal displacements (numpy), shared by the strain
diagnosis scripts."""
import numpy as np


def largest_principal_strain(xyz, conn, u, green_lagrange=False):
    """For each tet (conn: m x 4 node ids into xyz, undeformed positions; u: nodal displacements) the
    largest absolute principal strain: small strain (grad u + grad u^T) / 2, or with
    green_lagrange the Green-Lagrange strain (F^T F - I) / 2 that the large-deformation model uses."""
    X = xyz[conn]
    dX = np.stack([X[:, k] - X[:, 0] for k in (1, 2, 3)], axis=2)  # columns = edges
    U = u[conn]
    dU = np.stack([U[:, k] - U[:, 0] for k in (1, 2, 3)], axis=2)
    grad = dU @ np.linalg.inv(dX)  # grad u = dU * inv(dX)
    eps = 0.5 * (grad + np.transpose(grad, (0, 2, 1)))
    if green_lagrange:
        eps = eps + 0.5 * np.transpose(grad, (0, 2, 1)) @ grad
    return np.abs(np.linalg.eigvalsh(eps)).max(axis=1)
