// SPDX-License-Identifier: BSD-3-Clause
// The only translation unit that includes CGAL Mesh_3 (slow to compile).
#include "Copyleft/CGAL/LabeledImageMesher.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Image_3.h>
#include <CGAL/Labeled_mesh_domain_3.h>
#include <CGAL/Mesh_complex_3_in_triangulation_3.h>
#include <CGAL/Mesh_constant_domain_field_3.h>
#include <CGAL/Mesh_criteria_3.h>
#include <CGAL/Mesh_triangulation_3.h>
#include <CGAL/Random.h>
#include <CGAL/make_mesh_3.h>
#include <CGAL/version.h>

#include <cmath>
#include <cstring>
#include <unordered_map>

namespace faceplan {
namespace cgal {

namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Domain = CGAL::Labeled_mesh_domain_3<Kernel>;
using Triangulation = CGAL::Mesh_triangulation_3<Domain, CGAL::Default, CGAL::Sequential_tag>::type;
using Complex = CGAL::Mesh_complex_3_in_triangulation_3<Triangulation>;
using Criteria = CGAL::Mesh_criteria_3<Triangulation>;
using SizingField = CGAL::Mesh_constant_domain_field_3<Domain::R, Domain::Index>;
using Mesher = CGAL::Mesh_3::Mesher_3<Complex, Criteria, Domain>;

bool Cancelled(const std::atomic<bool>* cancel) {
  return cancel && cancel->load();
}

// Mesh_3's sizes are radii: a regular tetrahedron of edge h has circumradius h sqrt(6)/4, a
// regular triangle of edge h circumradius h / sqrt(3).
double CellRadius(double edge) {
  return edge * std::sqrt(6.0) / 4.0;
}
double FacetRadius(double edge) {
  return edge / std::sqrt(3.0);
}

const char* OptimisationMessage(CGAL::Mesh_optimization_return_code code) {
  switch (code) {
  case CGAL::TIME_LIMIT_REACHED:
    return "time limit reached";
  case CGAL::CANT_IMPROVE_ANYMORE:
    return "cannot improve further";
  default:
    return "";
  }
}

} // namespace

const char* CgalVersion() {
  return CGAL_VERSION_STR;
}

Status MeshLabeledImage(const LabelImage& image, const MeshingParameters& p, LabeledTetMesh& result,
                        std::atomic<bool>* cancel, const MeshingProgress& progress) {
  const ImageGrid& g = image.grid;
  if (image.labels.size() != g.numVoxels() || g.numVoxels() == 0)
    return Status::Error("the label image is empty or its size does not match its dimensions");
  auto report = [&](double f, const char* what) {
    if (progress)
      progress(f, what);
  };

  // The image is meshed in its own scaled frame (index times spacing); origin and direction are
  // applied to the result.
  _image* raw =
      ::_createImage(std::size_t(g.dims[0]), std::size_t(g.dims[1]), std::size_t(g.dims[2]), 1,
                     g.spacing[0], g.spacing[1], g.spacing[2], 1, WK_FIXED, SGN_UNSIGNED);
  if (!raw)
    return Status::Error("out of memory for the label image");
  std::memcpy(raw->data, image.labels.data(), image.labels.size());
  CGAL::Image_3 wrapped(raw); // owns `raw`

  CGAL::get_default_random() = CGAL::Random(p.seed);
  CGAL::Random domainRandom(p.seed);
  namespace params = CGAL::parameters;
  Domain domain = Domain::create_labeled_image_mesh_domain(
      wrapped, params::relative_error_bound = 1e-6, params::p_rng = &domainRandom);

  SizingField cellSize(CellRadius(p.cellSize));
  for (const auto& entry : p.labelCellSize)
    cellSize.set_size(CellRadius(entry.second), 3, entry.first);
  Criteria criteria(
      params::facet_angle = p.facetAngle, params::facet_size = FacetRadius(p.cellSize),
      params::facet_distance = p.surfaceDistance,
      params::cell_radius_edge_ratio = p.radiusEdgeRatio, params::cell_size = cellSize);

  Complex complex;
  report(0.05, "initial points");
  CGAL::Mesh_3::internal::init_c3t3(complex, domain, criteria, -1);
  if (Cancelled(cancel))
    return Status::Error("cancelled");

  report(0.1, "Delaunay refinement");
  CGAL::Mesh_error_code error = CGAL::CGAL_MESH_3_NO_ERROR;
  {
    Mesher mesher(complex, domain, criteria, 0,
                  std::size_t(std::max<long long>(0, p.maximumVertices)), &error, cancel);
    mesher.refine_mesh();
  }
  complex.clear_manifold_info();
  if (Cancelled(cancel))
    return Status::Error("cancelled");
  if (error == CGAL::CGAL_MESH_3_MAXIMAL_NUMBER_OF_VERTICES_REACHED)
    return Status::Error("the mesh reached its vertex budget (" +
                         std::to_string(p.maximumVertices) +
                         ") before meeting CellSize and SurfaceDistance: increase CellSize");
  if (complex.number_of_cells_in_complex() == 0)
    return Status::Error("Mesh_3 produced no tetrahedra (labels too thin for CellSize?)");

  Status status;
  auto note = [&](const char* phase, CGAL::Mesh_optimization_return_code code) {
    if (code == CGAL::TIME_LIMIT_REACHED)
      status.warnings.push_back(std::string(phase) + ": " + OptimisationMessage(code));
  };
  const int iterations = std::max(1, p.optimiserIterations);
  if (p.optimiser == MeshOptimiser::ODT) {
    report(0.6, "ODT smoothing");
    note("ODT",
         CGAL::odt_optimize_mesh_3(complex, domain, params::time_limit = p.optimiserTimeLimit,
                                   params::max_iteration_number = iterations));
  } else if (p.optimiser == MeshOptimiser::Lloyd) {
    report(0.6, "Lloyd smoothing");
    note("Lloyd",
         CGAL::lloyd_optimize_mesh_3(complex, domain, params::time_limit = p.optimiserTimeLimit,
                                     params::max_iteration_number = iterations));
  }
  if (Cancelled(cancel))
    return Status::Error("cancelled");
  if (p.perturb) {
    report(0.8, "sliver perturbation");
    CGAL::perturb_mesh_3(complex, domain, params::time_limit = p.optimiserTimeLimit,
                         params::sliver_bound = p.sliverBound);
  }
  if (Cancelled(cancel))
    return Status::Error("cancelled");
  if (p.exude) {
    report(0.9, "sliver exudation");
    CGAL::exude_mesh_3(complex, params::time_limit = p.optimiserTimeLimit,
                       params::sliver_bound = p.sliverBound);
  }
  if (Cancelled(cancel))
    return Status::Error("cancelled");

  // Cells of the complex, their vertices renumbered densely, in the physical frame.
  const Triangulation& tr = complex.triangulation();
  auto point = tr.geom_traits().construct_point_3_object();
  std::unordered_map<Triangulation::Vertex_handle, int> index;
  std::vector<Eigen::Vector3d> points;
  result.mesh.tets.resize(Eigen::Index(complex.number_of_cells_in_complex()), 4);
  result.tetLabel.clear();
  result.tetLabel.reserve(complex.number_of_cells_in_complex());
  Eigen::Index row = 0;
  for (auto c = complex.cells_in_complex_begin(); c != complex.cells_in_complex_end(); ++c, ++row) {
    for (int k = 0; k < 4; ++k) {
      const auto v = c->vertex(k);
      auto found = index.find(v);
      if (found == index.end()) {
        const auto& q = point(v->point());
        points.push_back(g.toWorld(Eigen::Vector3d(q.x(), q.y(), q.z())));
        found = index.emplace(v, int(points.size()) - 1).first;
      }
      result.mesh.tets(row, k) = found->second;
    }
    result.tetLabel.push_back(int(complex.subdomain_index(c)));
  }
  result.mesh.points.resize(Eigen::Index(points.size()), 3);
  for (std::size_t i = 0; i < points.size(); ++i)
    result.mesh.points.row(Eigen::Index(i)) = points[i].transpose();
  // A left-handed direction matrix mirrors the cells: make every one positive again.
  for (Eigen::Index e = 0; e < result.mesh.numTets(); ++e) {
    Eigen::Matrix3d m;
    for (int k = 0; k < 3; ++k)
      m.col(k) = (result.mesh.points.row(result.mesh.tets(e, k + 1)) -
                  result.mesh.points.row(result.mesh.tets(e, 0)))
                     .transpose();
    if (m.determinant() < 0)
      std::swap(result.mesh.tets(e, 1), result.mesh.tets(e, 2));
  }
  report(1.0, "meshed");
  return status;
}

} // namespace cgal
} // namespace faceplan
