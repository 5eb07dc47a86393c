// SPDX-License-Identifier: BSD-3-Clause
// Newton's method on the total potential energy, in each node's frame (LargeDeformationProblem.h).
// Prescribed DOFs get a unit row and column in the tangent, which keeps one sparsity pattern and
// one symbolic factorization for every iteration.
#include "CondensedFEM/LargeDeformation.h"

#include "Common/ExceptionBoundary.h"
#include "Common/ParallelFor.h"
#include "CondensedFEM/LargeDeformationProblem.h"
#include "CondensedFEM/NodeLayout.h"
#include "Element/NeoHookeanTet.h"
#include "Element/StiffnessAssembly.h"
#include "Mesh/InputValidation.h"
#include "SparseSolver/CholmodFactor.h"
#include "SparseSolver/FillReducingOrdering.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>
#include <sstream>

namespace faceplan {
namespace large_deformation {

namespace {

// A cell's packed tangent (global frame) turned into its nodes' frames: Q_a^T K_ab Q_b.
void ToNodeFrames(const Structure& st, const int* node, double* packed) {
  ElementMatrix k;
  const double* in = packed;
  for (int p = 0; p < 12; ++p)
    for (int q = p; q < 12; ++q)
      k(p, q) = k(q, p) = *in++;
  for (int a = 0; a < 4; ++a) {
    const int fa = st.frameOf[node[a]];
    if (fa >= 0) {
      const Eigen::Matrix3d& Q = st.frames[fa];
      k.middleRows<3>(3 * a) = (Q.transpose() * k.middleRows<3>(3 * a)).eval();
      k.middleCols<3>(3 * a) = (k.middleCols<3>(3 * a) * Q).eval();
    }
  }
  for (int p = 0; p < 12; ++p)
    for (int q = p; q < 12; ++q)
      *packed++ = k(p, q);
}

} // namespace

bool Evaluate(const Structure& st, const Eigen::VectorXd& u, Evaluation& out,
              std::vector<double>* packed, EvaluationScratch* scratch,
              const NearRestTangents* nearRest) {
  const TetMesh& mesh = *st.mesh;
  const std::int64_t m = mesh.numTets();
  EvaluationScratch local;
  EvaluationScratch& buffers = scratch ? *scratch : local;
  // A fixed number of cell ranges, each summing its cells' forces over its own nodes
  // (Structure::rangeNodes) in cell order, the ranges then added in order: the same sums on any
  // number of threads, and each range writes the nodes of neighbouring cells (a gather per node
  // from per-cell forces reads scattered memory and costs more than the cells' stress).
  const std::int64_t ranges =
      std::min<std::int64_t>(EvaluationScratch::kRanges, std::max<std::int64_t>(m, 1));
  if (static_cast<std::int64_t>(st.rangeNodes.size()) != ranges ||
      static_cast<std::int64_t>(st.cornerSlot.size()) != 4 * m)
    return false; // not a structure MakeStructure made
  buffers.energy.assign(static_cast<size_t>(ranges), 0.0);
  buffers.valid.assign(static_cast<size_t>(ranges), 1);
  buffers.force.resize(static_cast<size_t>(ranges));
  if (packed)
    packed->resize(static_cast<size_t>(m) * kPackedElementSize);
  if (!packed || (nearRest &&
                  (!nearRest->rest || !nearRest->held || nearRest->rest->size() != packed->size())))
    nearRest = nullptr;
  if (nearRest) {
    nearRest->held->resize(static_cast<size_t>(m), 0);
    buffers.order.resize(static_cast<size_t>(ranges));
  }
  ParallelFor(ranges, 2, [&](std::int64_t firstRange, std::int64_t lastRange) {
    CornerDisplacements corner;
    ElementMatrix tangent;
    NeoHookeanTetLanes lanes;
    double laneTangents[kPackedElementSize][kTetLanes];
    std::vector<int> nearCells; // a range's cells near rest, kept per thread
    // A cell near rest: its rest tangent into the buffer, unless the buffer holds it already.
    auto holdRest = [&](std::int64_t c) {
      char& held = (*nearRest->held)[c];
      if (!held) {
        const size_t at = static_cast<size_t>(c) * kPackedElementSize;
        std::copy_n(nearRest->rest->data() + at, kPackedElementSize, packed->data() + at);
        held = 1;
      }
    };
    for (std::int64_t r = firstRange; r < lastRange; ++r) {
      Eigen::VectorXd& force = buffers.force[r]; // over the range's nodes (Structure::rangeNodes)
      force.setZero(3 * static_cast<Eigen::Index>(st.rangeNodes[r].size()));
      double energy = 0.0;
      // Corner a of cell e's force (global frame) into the range's sum, in the node's frame.
      auto add = [&](std::int64_t e, const int* node, int a, Eigen::Vector3d f) {
        const int fa = st.frameOf[node[a]];
        if (fa >= 0)
          f = st.frames[fa].transpose() * f;
        force.segment<3>(3 * st.cornerSlot[static_cast<size_t>(4 * e + a)]) += f;
      };
      const std::int64_t begin = m * r / ranges, end = m * (r + 1) / ranges;
      // The cells in the order they are taken: the range's own, or with near-rest tangents the
      // cells that need their tangent first and those near rest after, so that four of a kind
      // share the lanes. nearFrom: where the near-rest cells start in that order.
      std::int64_t nearFrom = end - begin;
      const int* order = nullptr;
      if (nearRest) {
        std::vector<int>& list = buffers.order[r];
        list.clear();
        std::vector<int>& near = nearCells;
        near.clear();
        for (std::int64_t e = begin; e < end; ++e) {
          bool isNear = !st.smallStrain[e];
          if (isNear) {
            for (int a = 0; a < 4; ++a) {
              const int n = mesh.tets(e, a);
              corner.row(a) = st.toGlobal(n, u.segment<3>(3 * n)).transpose();
            }
            const Eigen::Matrix3d F = DeformationGradient(st.cells[e], corner);
            isNear = (F - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() <= nearRest->limit;
          }
          (isNear ? near : list).push_back(static_cast<int>(e));
        }
        nearFrom = static_cast<std::int64_t>(list.size());
        list.insert(list.end(), near.begin(), near.end());
        order = list.data();
      }
      auto cellAt = [&](std::int64_t i) { return order ? order[i] : begin + i; };
      const std::int64_t count = end - begin;
      for (std::int64_t i = 0; i < count;) {
        const std::int64_t e = cellAt(i);
        // Four neo-Hookean cells at a time: their forces, and their tangents when asked for
        // (not for cells near rest, which take their rest tangent).
        const bool near = i >= nearFrom;
        const bool withTangent = packed && !near;
        bool lanesOfAKind = i + kTetLanes <= count && (i >= nearFrom || i + kTetLanes <= nearFrom);
        for (int l = 0; l < kTetLanes && lanesOfAKind; ++l)
          lanesOfAKind = !st.smallStrain[cellAt(i + l)];
        if (lanesOfAKind) {
          int nodes[kTetLanes][4];
          for (int l = 0; l < kTetLanes; ++l) {
            const std::int64_t c = cellAt(i + l);
            const TetReference& cell = st.cells[c];
            for (int a = 0; a < 4; ++a) {
              nodes[l][a] = mesh.tets(c, a);
              const Eigen::Vector3d ua = st.toGlobal(nodes[l][a], u.segment<3>(3 * nodes[l][a]));
              for (int i = 0; i < 3; ++i) {
                lanes.corner[a][i][l] = ua[i];
                lanes.gradient[a][i][l] = cell.gradients(a, i);
              }
            }
            lanes.volume[l] = cell.volume;
            lanes.mu[l] = st.materials[c].mu;
            lanes.kappa[l] = st.materials[c].kappa;
          }
          if (!(withTangent ? NeoHookeanTetForcesAndTangents(lanes, laneTangents)
                            : NeoHookeanTetForces(lanes))) {
            buffers.valid[r] = 0;
            break;
          }
          for (int l = 0; l < kTetLanes; ++l) {
            energy += lanes.energy[l];
            for (int a = 0; a < 4; ++a)
              add(cellAt(i + l), nodes[l], a,
                  Eigen::Vector3d(lanes.force[a][0][l], lanes.force[a][1][l],
                                  lanes.force[a][2][l]));
            const std::int64_t c = cellAt(i + l);
            if (withTangent) {
              double* o = packed->data() + static_cast<size_t>(c) * kPackedElementSize;
              for (int k = 0; k < kPackedElementSize; ++k)
                o[k] = laneTangents[k][l];
              if (std::any_of(nodes[l], nodes[l] + 4, [&](int n) { return st.frameOf[n] >= 0; }))
                ToNodeFrames(st, nodes[l], o);
              if (nearRest)
                (*nearRest->held)[c] = 0;
            } else if (packed) {
              holdRest(c);
            }
          }
          i += kTetLanes;
          continue;
        }
        int node[4];
        for (int a = 0; a < 4; ++a) {
          node[a] = mesh.tets(e, a);
          corner.row(a) = st.toGlobal(node[a], u.segment<3>(3 * node[a])).transpose();
        }
        ElementVector f;
        double cellEnergy = 0.0;
        const bool state =
            st.smallStrain[e] ? SmallStrainTetState(st.cells[e], st.materials[e], corner,
                                                    cellEnergy, f, withTangent ? &tangent : nullptr)
                              : NeoHookeanTetState(st.cells[e], st.materials[e], corner, cellEnergy,
                                                   f, withTangent ? &tangent : nullptr);
        if (!state) {
          buffers.valid[r] = 0;
          break;
        }
        energy += cellEnergy;
        for (int a = 0; a < 4; ++a) {
          const int fa = st.frameOf[node[a]];
          if (withTangent && fa >= 0) {
            const Eigen::Matrix3d& Q = st.frames[fa];
            tangent.middleRows<3>(3 * a) = (Q.transpose() * tangent.middleRows<3>(3 * a)).eval();
            tangent.middleCols<3>(3 * a) = (tangent.middleCols<3>(3 * a) * Q).eval();
          }
          add(e, node, a, f.segment<3>(3 * a));
        }
        if (withTangent) {
          double* o = packed->data() + static_cast<size_t>(e) * kPackedElementSize;
          for (int p = 0; p < 12; ++p)
            for (int q = p; q < 12; ++q)
              *o++ = tangent(p, q);
          if (nearRest)
            (*nearRest->held)[e] = 0;
        } else if (packed) {
          holdRest(e);
        }
        ++i;
      }
      buffers.energy[r] = energy;
    }
  });
  if (std::find(buffers.valid.begin(), buffers.valid.end(), 0) != buffers.valid.end())
    return false;
  out.energy = 0.0;
  out.force.setZero(3 * st.n);
  for (std::int64_t r = 0; r < ranges; ++r) {
    out.energy += buffers.energy[r];
    const std::vector<int>& nodes = st.rangeNodes[r];
    const double* f = buffers.force[r].data();
    double* sum = out.force.data();
    for (size_t k = 0; k < nodes.size(); ++k)
      for (int c = 0; c < 3; ++c)
        sum[3 * nodes[k] + c] += f[3 * k + c];
  }
  return std::isfinite(out.energy) && out.force.allFinite();
}

void ZeroPrescribed(const std::vector<char>& prescribed, Eigen::Ref<Eigen::VectorXd> v) {
  // A select and a store for every entry: the prescribed DOFs lie among the free ones without a
  // pattern, and a branch on each would be mispredicted about as often as taken.
  double* x = v.data();
  const char* pinned = prescribed.data();
  for (Eigen::Index i = 0; i < v.size(); ++i)
    x[i] = pinned[i] ? 0.0 : x[i];
}

void FindPinnedEntries(const SparseMatrix& upper, const std::vector<char>& prescribed,
                       std::vector<int>& entries, std::vector<int>& diagonal) {
  entries.clear();
  diagonal.clear();
  for (int col = 0; col < upper.outerSize(); ++col)
    for (int k = upper.outerIndexPtr()[col]; k < upper.outerIndexPtr()[col + 1]; ++k) {
      const int row = upper.innerIndexPtr()[k];
      if (row == col && prescribed[col])
        diagonal.push_back(k);
      else if (prescribed[row] || prescribed[col])
        entries.push_back(k);
    }
}

namespace {

// For lift-off the normal must point from the bone into the tissue: the side where the node's
// cells lie (the sum of their centroids' offsets from the node).
Eigen::Vector3d IntoTissue(const TetMesh& mesh, const std::vector<std::vector<int>>& cellsOfNode,
                           int node, const Eigen::Vector3d& normal) {
  Eigen::Vector3d towardCells = Eigen::Vector3d::Zero();
  for (int e : cellsOfNode[node]) {
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
    for (int a = 0; a < 4; ++a)
      centroid += mesh.points.row(mesh.tets(e, a)).transpose();
    towardCells += 0.25 * centroid - mesh.points.row(node).transpose();
  }
  return normal.dot(towardCells) < 0.0 ? Eigen::Vector3d(-normal) : normal;
}

// The cells in the order of their centroids' Morton codes (ties by index).
std::vector<int> SpaceFillingCellOrder(const TetMesh& mesh) {
  const Eigen::Index m = mesh.numTets();
  std::vector<int> order(static_cast<size_t>(m));
  std::iota(order.begin(), order.end(), 0);
  if (m == 0)
    return order;
  Eigen::MatrixX3d centroid(m, 3);
  for (Eigen::Index e = 0; e < m; ++e)
    centroid.row(e) = 0.25 * (mesh.points.row(mesh.tets(e, 0)) + mesh.points.row(mesh.tets(e, 1)) +
                              mesh.points.row(mesh.tets(e, 2)) + mesh.points.row(mesh.tets(e, 3)));
  const Eigen::RowVector3d low = centroid.colwise().minCoeff();
  const double extent = (centroid.colwise().maxCoeff() - low).maxCoeff();
  const double scale = extent > 0.0 ? 1023.0 / extent : 0.0;
  auto spread = [](std::uint64_t v) { // 10 bits to every third of 30
    v &= 0x3ff;
    v = (v | (v << 16)) & 0x30000ff;
    v = (v | (v << 8)) & 0x300f00f;
    v = (v | (v << 4)) & 0x30c30c3;
    v = (v | (v << 2)) & 0x9249249;
    return v;
  };
  std::vector<std::uint64_t> key(static_cast<size_t>(m));
  for (Eigen::Index e = 0; e < m; ++e) {
    std::uint64_t code = 0;
    for (int i = 0; i < 3; ++i) {
      const double q = std::clamp((centroid(e, i) - low[i]) * scale, 0.0, 1023.0);
      code |= spread(static_cast<std::uint64_t>(q)) << i;
    }
    key[static_cast<size_t>(e)] = code;
  }
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return key[a] < key[b]; });
  return order;
}

} // namespace

Status MakeStructure(const PrecomputeRequest& request, bool liftOff, Structure& st) {
  const NodeSets& sets = request.sets;
  st.meshCell = SpaceFillingCellOrder(request.mesh);
  auto ordered = std::make_shared<TetMesh>();
  ordered->points = request.mesh.points;
  ordered->tets.resize(request.mesh.numTets(), 4);
  for (size_t e = 0; e < st.meshCell.size(); ++e)
    ordered->tets.row(static_cast<Eigen::Index>(e)) = request.mesh.tets.row(st.meshCell[e]);
  st.ownMesh = ordered;
  st.mesh = st.ownMesh.get();
  const TetMesh& mesh = *st.mesh;
  st.n = mesh.numPoints();
  const Eigen::Index n = st.n;
  st.frameOf.assign(n, -1);
  std::vector<std::vector<int>> cellsOfNode(liftOff ? n : 0);
  for (Eigen::Index e = 0; liftOff && e < mesh.numTets(); ++e)
    for (int a = 0; a < 4; ++a)
      cellsOfNode[mesh.tets(e, a)].push_back(static_cast<int>(e));
  for (size_t s = 0; s < sets.sliding.size(); ++s) {
    const int node = sets.sliding[s];
    st.frameOf[node] = static_cast<int>(st.frames.size());
    st.frames.push_back(NormalFrame(liftOff
                                        ? IntoTissue(mesh, cellsOfNode, node, sets.slidingNormal[s])
                                        : sets.slidingNormal[s]));
    if (liftOff)
      st.liftOffDofs.push_back(3 * node);
  }
  st.prescribed.assign(3 * n, 0);
  std::vector<char> used(n, 0);
  for (Eigen::Index e = 0; e < mesh.numTets(); ++e)
    for (int a = 0; a < 4; ++a)
      used[mesh.tets(e, a)] = 1;
  for (Eigen::Index i = 0; i < n; ++i)
    if (!used[i])
      st.prescribed[3 * i] = st.prescribed[3 * i + 1] = st.prescribed[3 * i + 2] = 1;
  for (int node : sets.constrained) {
    const int dofs = st.frameOf[node] >= 0 ? 1 : 3;
    for (int c = 0; c < dofs; ++c)
      st.prescribed[3 * node + c] = 1;
  }
  st.cells.resize(static_cast<size_t>(mesh.numTets()));
  st.materials.resize(st.cells.size());
  st.cellMass.resize(st.cells.size());
  st.smallStrain.resize(st.cells.size());
  TetCorners corners;
  for (Eigen::Index e = 0; e < mesh.numTets(); ++e) {
    for (int a = 0; a < 4; ++a)
      corners.row(a) = mesh.points.row(mesh.tets(e, a));
    const Eigen::Index c = st.meshCell[static_cast<size_t>(e)];
    st.cells[e] = MakeTetReference(corners);
    st.materials[e] = NeoHookeanFromLinear(request.materials.E(c), request.materials.nu(c));
    st.cellMass[e] = request.materials.rho(c) * st.cells[e].volume;
    st.smallStrain[e] = request.materials.isSmallStrain(c) ? 1 : 0;
  }
  const std::int64_t m = mesh.numTets();
  const std::int64_t ranges =
      std::min<std::int64_t>(EvaluationScratch::kRanges, std::max<std::int64_t>(m, 1));
  st.rangeNodes.assign(static_cast<size_t>(ranges), {});
  st.cornerSlot.assign(static_cast<size_t>(4 * m), 0);
  std::vector<int> slot(static_cast<size_t>(n), -1);
  for (std::int64_t r = 0; r < ranges; ++r) {
    const std::int64_t begin = m * r / ranges, end = m * (r + 1) / ranges;
    std::vector<int>& nodes = st.rangeNodes[static_cast<size_t>(r)];
    for (std::int64_t e = begin; e < end; ++e)
      for (int a = 0; a < 4; ++a)
        nodes.push_back(mesh.tets(e, a));
    std::sort(nodes.begin(), nodes.end());
    nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
    for (size_t k = 0; k < nodes.size(); ++k)
      slot[static_cast<size_t>(nodes[k])] = static_cast<int>(k);
    for (std::int64_t e = begin; e < end; ++e)
      for (int a = 0; a < 4; ++a)
        st.cornerSlot[static_cast<size_t>(4 * e + a)] = slot[static_cast<size_t>(mesh.tets(e, a))];
  }
  return Status::Ok();
}

Status MakePattern(const Structure& st, AssemblyPattern& pattern) {
  std::vector<int> identity(st.n);
  std::iota(identity.begin(), identity.end(), 0);
  return BuildAssemblyPattern(*st.mesh, identity, static_cast<int>(st.n), pattern);
}

Status SetValues(const PrecomputeRequest& request, const SolveInput& input, Problem& pb) {
  const Structure& st = *pb.st;
  const TetMesh& mesh = *st.mesh;
  const NodeSets& sets = request.sets;
  const Eigen::Index n = st.n;
  pb.target = Eigen::VectorXd::Zero(3 * n);
  for (size_t k = 0; k < sets.movable.size(); ++k) {
    const int node = sets.movable[k];
    const Eigen::Vector3d local =
        st.toLocal(node, input.movableDisplacement.row(static_cast<Eigen::Index>(k)).transpose());
    const int dofs = st.frameOf[node] >= 0 ? 1 : 3;
    pb.target.segment(3 * node, dofs) = local.head(dofs);
  }
  const bool gravity = input.gravity.squaredNorm() > 0.0;
  if (!gravity && input.nodalLoads.size() == 0) {
    pb.externalLoad.setZero(3 * n);
    return Status::Ok();
  }
  Eigen::VectorXd load = Eigen::VectorXd::Zero(3 * n);
  if (gravity)
    for (Eigen::Index e = 0; e < mesh.numTets(); ++e)
      for (int a = 0; a < 4; ++a)
        load.segment<3>(3 * mesh.tets(e, a)) += st.cellMass[e] / 4.0 * input.gravity;
  if (input.nodalLoads.size() > 0) {
    if (input.nodalLoads.rows() != n || !input.nodalLoads.allFinite())
      return Status::Error("nodal loads must be finite, one row per mesh point");
    for (Eigen::Index i = 0; i < n; ++i)
      load.segment<3>(3 * i) += input.nodalLoads.row(i).transpose();
  }
  pb.externalLoad.resize(3 * n);
  for (Eigen::Index i = 0; i < n; ++i)
    pb.externalLoad.segment<3>(3 * i) = st.toLocal(static_cast<int>(i), load.segment<3>(3 * i));
  return Status::Ok();
}

void BalanceInto(const Problem& pb, const Evaluation& ev, const Eigen::VectorXd& u, double s,
                 Balance& b) {
  // One pass over the vectors (an iteration's hot path reads them from memory, not cache).
  const Eigen::Index n = u.size();
  b.residual.resize(n);
  const double* force = ev.force.data();
  const double* load = pb.externalLoad.data();
  const double* x = u.data();
  const char* pinned = pb.prescribed.data();
  double* r = b.residual.data();
  double work = 0.0, rr = 0.0, ff = 0.0, ll = 0.0;
  for (Eigen::Index i = 0; i < n; ++i) {
    work += load[i] * x[i];
    ff += force[i] * force[i];
    ll += load[i] * load[i];
    const double ri = pinned[i] ? 0.0 : force[i] - s * load[i];
    r[i] = ri;
    rr += ri * ri;
  }
  b.potential = ev.energy - s * work;
  b.residualNorm = std::sqrt(rr);
  b.scale = std::max(
      {std::sqrt(ff), s * std::sqrt(ll), pb.linearForce, kRoundOffStrain * pb.st->unitStrainForce});
}

Balance BalanceOf(const Problem& pb, const Evaluation& ev, const Eigen::VectorXd& u, double s) {
  Balance b;
  BalanceInto(pb, ev, u, s, b);
  return b;
}

bool UpdateContact(Problem& pb, const Eigen::VectorXd& u, double s, const Eigen::VectorXd* force) {
  if (pb.st->liftOffDofs.empty())
    return false;
  Evaluation ev;
  if (force && force->size() == u.size())
    ev.force = *force;
  else if (!Evaluate(*pb.st, u, ev, nullptr))
    return false;
  const Eigen::VectorXd reaction = ev.force - s * pb.externalLoad;
  const double forceTolerance = 1e-12 * std::max(ev.force.norm(), pb.linearForce);
  const double gapTolerance = 1e-12 * std::max(1.0, pb.target.cwiseAbs().maxCoeff());
  bool changed = false;
  for (int dof : pb.st->liftOffDofs) {
    if (pb.prescribed[dof] && reaction[dof] < -forceTolerance) {
      pb.prescribed[dof] = 0;
      changed = true;
    } else if (!pb.prescribed[dof] && u[dof] < s * pb.target[dof] - gapTolerance) {
      pb.prescribed[dof] = 1;
      changed = true;
    }
  }
  return changed;
}

DeformationMeasures MeasureDeformation(const Structure& st, const Eigen::VectorXd& u) {
  const TetMesh& mesh = *st.mesh;
  const std::int64_t m = mesh.numTets();
  // One partial result per contiguous range, merged in order: the same cell as a serial scan.
  const std::int64_t ranges = 64;
  std::vector<DeformationMeasures> part(static_cast<size_t>(ranges));
  ParallelFor(ranges, 2, [&](std::int64_t firstRange, std::int64_t lastRange) {
    CornerDisplacements corner;
    for (std::int64_t k = firstRange; k < lastRange; ++k) {
      DeformationMeasures& r = part[static_cast<size_t>(k)];
      r.smallestVolumeRatio = std::numeric_limits<double>::infinity();
      const std::int64_t begin = k * m / ranges, end = (k + 1) * m / ranges;
      for (std::int64_t e = begin; e < end; ++e) {
        for (int a = 0; a < 4; ++a) {
          const int node = mesh.tets(e, a);
          corner.row(a) = st.toGlobal(node, u.segment<3>(3 * node)).transpose();
        }
        const Eigen::Matrix3d F = DeformationGradient(st.cells[e], corner);
        r.smallestVolumeRatio = std::min(r.smallestVolumeRatio, F.determinant());
        const Eigen::Matrix3d green = 0.5 * (F.transpose() * F - Eigen::Matrix3d::Identity());
        // A symmetric matrix's eigenvalues are at most its Frobenius norm in magnitude: a cell
        // whose norm (with a margin far above the eigensolver's round-off) does not exceed the
        // range's largest so far cannot replace it, and skips the eigensolver, the measure's
        // costliest part. The result is the cell-by-cell scan's.
        if (green.norm() * (1.0 + 1e-10) <= r.largestGreenStrain)
          continue;
        // The closed form for 3 x 3 (a few ulps from the iterative solver, many times faster).
        Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen;
        eigen.computeDirect(green, Eigen::EigenvaluesOnly);
        const double largest = eigen.eigenvalues().cwiseAbs().maxCoeff();
        if (largest > r.largestGreenStrain ||
            (largest == r.largestGreenStrain && st.requestCell(e) < r.largestStrainCell)) {
          r.largestGreenStrain = largest;
          r.largestStrainCell = st.requestCell(e);
        }
      }
    }
  });
  DeformationMeasures r;
  r.smallestVolumeRatio = std::numeric_limits<double>::infinity();
  for (const DeformationMeasures& p : part) {
    r.smallestVolumeRatio = std::min(r.smallestVolumeRatio, p.smallestVolumeRatio);
    if (p.largestGreenStrain > r.largestGreenStrain ||
        (p.largestGreenStrain == r.largestGreenStrain &&
         p.largestStrainCell < r.largestStrainCell)) {
      r.largestGreenStrain = p.largestGreenStrain;
      r.largestStrainCell = p.largestStrainCell;
    }
  }
  return r;
}

double RestForceNorm(const SparseMatrix& restUpper, const Eigen::VectorXd& v) {
  return (restUpper.selfadjointView<Eigen::Upper>() * v).norm();
}

Eigen::VectorXd LocalPositions(const Structure& st) {
  Eigen::VectorXd positions(3 * st.n);
  for (Eigen::Index i = 0; i < st.n; ++i)
    positions.segment<3>(3 * i) =
        st.toLocal(static_cast<int>(i), st.mesh->points.row(i).transpose());
  return positions;
}

Status FinishSolve(const PrecomputeRequest& request, const SolveInput& input, const Problem& pb,
                   const Eigen::VectorXd& u, double relativeResidual, SolveResult& result,
                   FinalState& finalState, const DeformationMeasures* measured) {
  const Structure& st = *pb.st;
  finalState.measures = measured ? *measured : MeasureDeformation(st, u);
  finalState.liftedNodes = 0;
  for (int dof : st.liftOffDofs)
    finalState.liftedNodes += pb.prescribed[dof] ? 0 : 1;
  result.relativeResidual = relativeResidual;
  result.largestStrain = finalState.measures.largestGreenStrain;
  result.invertedCells = 0;
  return FillResult(request, input, st, u, result);
}

Status FillResult(const PrecomputeRequest& request, const SolveInput& input, const Structure& st,
                  const Eigen::VectorXd& u, SolveResult& result) {
  const Eigen::Index n = st.n;
  RowVectors3d all(n, 3);
  for (Eigen::Index i = 0; i < n; ++i)
    all.row(i) = st.toGlobal(static_cast<int>(i), u.segment<3>(3 * i)).transpose();
  if (!all.allFinite())
    return Status::Error("the large-deformation solve produced non-finite values");
  result.keptDisplacement.resize(static_cast<Eigen::Index>(request.sets.kept.size()), 3);
  for (size_t k = 0; k < request.sets.kept.size(); ++k)
    result.keptDisplacement.row(static_cast<Eigen::Index>(k)) = all.row(request.sets.kept[k]);
  if (input.recoverInterior)
    result.allDisplacement = std::move(all);
  return Status::Ok();
}

} // namespace large_deformation

namespace {

using namespace large_deformation;

// Newton's own problem: the shared values plus the tangent's pattern and its pinned entries.
struct NewtonProblem : Problem {
  AssemblyPattern pattern;
  std::vector<int> prescribedEntries; // nonzeros of the upper triangle in a prescribed row/column
  std::vector<int> prescribedDiagonal;
  void findPinned() {
    FindPinnedEntries(pattern.upper, prescribed, prescribedEntries, prescribedDiagonal);
  }
};

// The tangent with unit rows and columns for the prescribed DOFs.
void PinPrescribed(NewtonProblem& pb) {
  double* values = pb.pattern.upper.valuePtr();
  for (int k : pb.prescribedEntries)
    values[k] = 0.0;
  for (int k : pb.prescribedDiagonal)
    values[k] = 1.0;
}

struct StepState {
  Eigen::VectorXd u;   // nodes' frames
  double fraction = 0; // of the prescribed values and loads
};

class NewtonSolver {
public:
  NewtonSolver(NewtonProblem& pb, const LargeDeformationOptions& options, CholmodFactor& factor,
               LargeDeformationReport& report, StageTimings& timings)
      : pb_(pb), options_(options), factor_(factor), report_(report), timings_(timings) {}

  // From a converged state at `from` to the load fraction `to`. True when converged there.
  bool step(const StepState& from, double to, double tolerance, StepState& reached, Status& error) {
    Evaluation ev;
    Eigen::VectorXd u = from.u;
    if (!evaluate(u, ev, true))
      return false;
    // Predictor: the prescribed DOFs move to their new values and the free ones follow the
    // tangent's response, K_ff du_f = -(r_f + K_fp du_p - ds f_ext,f).
    Eigen::VectorXd prescribedMove = Eigen::VectorXd::Zero(u.size());
    for (Eigen::Index i = 0; i < u.size(); ++i)
      if (pb_.prescribed[i])
        prescribedMove[i] = to * pb_.target[i] - u[i];
    Eigen::VectorXd rhs = pb_.pattern.upper.selfadjointView<Eigen::Upper>() * prescribedMove;
    rhs += ev.force - to * pb_.externalLoad;
    rhs = -rhs;
    ZeroPrescribed(pb_.prescribed, rhs);
    Eigen::VectorXd du;
    if (!solveTangent(rhs, du, error))
      return false;
    du += prescribedMove;
    u += du;
    for (int it = 0; it < options_.maxIterationsPerStep; ++it) {
      if (!evaluate(u, ev, true))
        return false; // the predictor inverted a cell: a smaller step
      const Balance b = BalanceOf(pb_, ev, u, to);
      lastResidual_ = b.scale > 0.0 ? b.residualNorm / b.scale : 0.0;
      report_.convergence.emplace_back(clock_.elapsedMs(), lastResidual_);
      if (b.residualNorm <= tolerance * b.scale) {
        reached.u = u;
        reached.fraction = to;
        lastIterations_ = it;
        return true;
      }
      ++report_.newtonIterations;
      if (!solveTangent(-b.residual, du, error))
        return false;
      // Backtracking: accept a step that keeps every cell valid and lowers the potential or the
      // residual (near convergence the potential's change is below round-off).
      const double slope = b.residual.dot(du);
      bool accepted = false;
      for (double alpha = 1.0; alpha >= 1.0 / 1024.0; alpha *= 0.5) {
        const Eigen::VectorXd trial = u + alpha * du;
        Evaluation tev;
        if (!evaluate(trial, tev, false))
          continue;
        const Balance tb = BalanceOf(pb_, tev, trial, to);
        if (tb.potential <= b.potential + 1e-4 * alpha * slope ||
            tb.residualNorm < 0.5 * b.residualNorm) {
          u = trial;
          accepted = true;
          break;
        }
      }
      if (!accepted)
        return false;
    }
    return false;
  }

  int lastIterations() const { return lastIterations_; }
  double lastResidual() const { return lastResidual_; }

private:
  bool evaluate(const Eigen::VectorXd& u, Evaluation& ev, bool withTangent) {
    StageClock clock;
    const bool ok = Evaluate(*pb_.st, u, ev, withTangent ? &packed_ : nullptr, &scratch_);
    timings_[Stage::ElementStiffness].ms += clock.lapMs();
    if (ok && withTangent) {
      AssembleFromPacked(packed_.data(), pb_.pattern);
      timings_[Stage::Assembly].ms += clock.lapMs();
    }
    return ok;
  }

  // Solves the pinned tangent for a right-hand side that is zero on the prescribed DOFs. False
  // (a smaller step) when the tangent is not positive definite; `error` is set only for failures
  // a smaller step cannot mend.
  bool solveTangent(const Eigen::VectorXd& rhs, Eigen::VectorXd& du, Status& error) {
    StageClock clock;
    PinPrescribed(pb_);
    const Status factored = factor_.factorize(pb_.pattern.upper);
    timings_[Stage::Factorization].ms += clock.lapMs();
    if (!factored)
      return false;
    Eigen::MatrixXd x;
    const Status solved = factor_.solve(rhs, x);
    timings_[Stage::Solve].ms += clock.lapMs();
    if (!solved) {
      error = solved;
      return false;
    }
    du = x.col(0);
    ZeroPrescribed(pb_.prescribed, du);
    return du.allFinite();
  }

  NewtonProblem& pb_;
  const LargeDeformationOptions& options_;
  CholmodFactor& factor_;
  LargeDeformationReport& report_;
  StageTimings& timings_;
  std::vector<double> packed_;
  EvaluationScratch scratch_;
  int lastIterations_ = 0;
  double lastResidual_ = 0.0;
  StageClock clock_;
};

Status LargeDeformationImpl(const PrecomputeRequest& request, const SolveInput& input,
                            const LargeDeformationOptions& options, SolveResult& result,
                            LargeDeformationReport& report) {
  StageClock total, clock;
  result = SolveResult();
  report = LargeDeformationReport();
  result.method = SolveMethod::LargeDeformationNewton;
  result.backend = "CPU";
  if (request.options.elementOrder != ElementOrder::Linear)
    return Status::Error("the large-deformation model supports linear (4-node) elements only");
  if (!(options.tolerance > 0.0) || !(options.initialStep > 0.0) || options.initialStep > 1.0 ||
      options.maxIterationsPerStep < 1 || options.maxStepHalvings < 0 || options.maxLoadSteps < 1 ||
      options.maxTotalIterations < 1 || options.maxContactUpdatesPerStep < 0 ||
      options.maxContactUpdates < 0)
    return Status::Error("invalid large-deformation options");
  Status status = ValidateSolveInputs(request.mesh, request.materials, request.sets);
  if (!status)
    return status;
  if (input.movableDisplacement.rows() != static_cast<Eigen::Index>(request.sets.movable.size()))
    return Status::Error("expected one ROI displacement per movable node");
  if (!input.movableDisplacement.allFinite() || !input.gravity.allFinite())
    return Status::Error("prescribed displacements or loads contain NaN or infinite values");

  NewtonProblem pb;
  auto structure = std::make_shared<Structure>();
  status = MakeStructure(request, options.slidingLiftOff, *structure);
  if (status)
    status = MakePattern(*structure, pb.pattern);
  if (!status)
    return status;
  pb.prescribed = structure->prescribed;
  pb.st = structure;
  status = SetValues(request, input, pb);
  if (!status)
    return status;
  pb.findPinned();
  const Structure& st = *pb.st;
  result.timings[Stage::Separation].ms = clock.lapMs();
  CholmodFactor factor;
  // METIS on the node graph, as the linear model's factor (SparseSolver/FillReducingOrdering.h).
  FillReducingOrdering ordering;
  status = OrderNodesWithTrailing(pb.pattern.upper, 3, {}, ordering);
  if (status)
    status = factor.analyze(pb.pattern.upper, &ordering);
  if (!status)
    return status;
  result.timings[Stage::Reordering].ms = clock.lapMs();

  NewtonSolver newton(pb, options, factor, report, result.timings);
  StepState state;
  state.u = Eigen::VectorXd::Zero(3 * st.n);
  {
    Evaluation rest;
    std::vector<double> packed;
    Evaluate(st, state.u, rest, &packed);
    AssembleFromPacked(packed.data(), pb.pattern);
    pb.linearForce = RestForceNorm(pb.pattern.upper, pb.target);
    structure->unitStrainForce = RestForceNorm(pb.pattern.upper, LocalPositions(st));
  }
  double step = options.initialStep;
  int halvings = 0;
  while (state.fraction < 1.0) {
    if (report.loadSteps + report.rejectedSteps >= options.maxLoadSteps)
      return Status::Error("the large-deformation solve needed more than " +
                           std::to_string(options.maxLoadSteps) + " load steps");
    if (report.contactUpdates >= options.maxContactUpdates)
      return Status::Error("the large-deformation solve did not converge: the lift-off contact "
                           "changed " +
                           std::to_string(report.contactUpdates) +
                           " times without settling (check the sliding normals)");
    if (report.newtonIterations >= options.maxTotalIterations)
      return Status::Error("the large-deformation solve did not converge within " +
                           std::to_string(options.maxTotalIterations) + " Newton iterations");
    const double to = std::min(1.0, state.fraction + step);
    StepState reached;
    Status failure;
    // With lift-off the contact is settled on loosely converged states (it changes a few times)
    // and the last solve converges fully; a contact change after it starts the loop again.
    const double settleTolerance =
        st.liftOffDofs.empty() ? options.tolerance : std::max(options.tolerance, kSettleTolerance);
    if (newton.step(state, to, settleTolerance, reached, failure)) {
      int updates = 0;
      bool settled = true, tight = settleTolerance == options.tolerance;
      while (true) {
        const bool changed = UpdateContact(pb, reached.u, to);
        if (changed)
          pb.findPinned();
        if (!changed && tight)
          break;
        if (changed)
          ++report.contactUpdates;
        const StepState start = reached;
        tight = !changed;
        if (++updates > options.maxContactUpdatesPerStep ||
            !newton.step(start, to, tight ? options.tolerance : settleTolerance, reached,
                         failure)) {
          settled = false;
          break;
        }
      }
      if (!failure.ok)
        return failure;
      if (settled) {
        state = reached;
        ++report.loadSteps;
        if (options.progress)
          options.progress(state.fraction);
        halvings = 0;
        if (newton.lastIterations() <= 6)
          step = std::min(1.0, 2.0 * step);
        continue;
      }
      // The contact kept changing: a smaller step, starting from the contact reached so far.
    }
    if (!failure.ok)
      return failure;
    ++report.rejectedSteps;
    if (++halvings > options.maxStepHalvings) {
      std::ostringstream why;
      why << "the large-deformation solve did not converge: it reached " << 100.0 * state.fraction
          << " % of the prescribed move, and smaller load steps could not go further (a cell "
             "would invert, or the lift-off contact did not settle)";
      return Status::Error(why.str());
    }
    step *= 0.5;
  }

  FinalState finalState;
  status = FinishSolve(request, input, pb, state.u, newton.lastResidual(), result, finalState);
  report.smallestVolumeRatio = finalState.measures.smallestVolumeRatio;
  report.largestGreenStrain = finalState.measures.largestGreenStrain;
  report.largestStrainCell = finalState.measures.largestStrainCell;
  report.liftedNodes = finalState.liftedNodes;
  if (!status)
    return status;
  result.timings[Stage::Total].ms = total.elapsedMs();
  return Status::Ok();
}

} // namespace

Status SolveLargeDeformation(const PrecomputeRequest& request, const SolveInput& input,
                             const LargeDeformationOptions& options, SolveResult& result,
                             LargeDeformationReport& report) {
  return ReturnStatusOnException("the large-deformation solve", [&]() -> Status {
    return LargeDeformationImpl(request, input, options, result, report);
  });
}

} // namespace faceplan
