// SPDX-License-Identifier: BSD-3-Clause
// Writes the face-like shell scene of faceplan_benchmark (Testing/Support/ShellMeshGenerator) as a
// legacy-VTK unstructured grid, so that pvpython benchmarks can run the same scene through the
// ParaView pipeline. Point array `Layer`: 0 on the inner (bone-side) sphere.
//   export_shell_scene --subdivisions S --layers L --out scene.vtk
#include "Support/ShellMeshGenerator.h"

#include <cstdio>
#include <string>

int main(int argc, char** argv) {
  int subdivisions = 18, layers = 5;
  std::string out;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string key = argv[i], value = argv[i + 1];
    if (key == "--subdivisions")
      subdivisions = std::stoi(value);
    else if (key == "--layers")
      layers = std::stoi(value);
    else if (key == "--out")
      out = value;
    else {
      std::fprintf(stderr, "unknown option %s\n", key.c_str());
      return 2;
    }
  }
  if (out.empty() || subdivisions < 1 || layers < 1) {
    std::fprintf(stderr, "usage: export_shell_scene --subdivisions S --layers L --out file.vtk\n");
    return 2;
  }
  const faceplan::FaceLikeScene scene = faceplan::MakeFaceLikeScene(subdivisions, layers, 0.1);
  const faceplan::TetMesh& mesh = scene.shell.mesh;
  std::FILE* f = std::fopen(out.c_str(), "w");
  if (!f) {
    std::fprintf(stderr, "cannot write %s\n", out.c_str());
    return 1;
  }
  const long long n = mesh.points.rows(), m = mesh.tets.rows();
  std::fprintf(f, "# vtk DataFile Version 3.0\nFacePlan shell scene\nASCII\n");
  std::fprintf(f, "DATASET UNSTRUCTURED_GRID\nPOINTS %lld double\n", n);
  for (long long i = 0; i < n; ++i)
    std::fprintf(f, "%.17g %.17g %.17g\n", mesh.points(i, 0), mesh.points(i, 1), mesh.points(i, 2));
  std::fprintf(f, "CELLS %lld %lld\n", m, 5 * m);
  for (long long c = 0; c < m; ++c)
    std::fprintf(f, "4 %d %d %d %d\n", mesh.tets(c, 0), mesh.tets(c, 1), mesh.tets(c, 2),
                 mesh.tets(c, 3));
  std::fprintf(f, "CELL_TYPES %lld\n", m);
  for (long long c = 0; c < m; ++c)
    std::fprintf(f, "10\n");
  std::fprintf(f, "POINT_DATA %lld\nSCALARS Layer int 1\nLOOKUP_TABLE default\n", n);
  for (long long i = 0; i < n; ++i)
    std::fprintf(f, "%lld\n", i / scene.shell.nodesPerLayer);
  std::fclose(f);
  std::printf("%s: %lld points, %lld tetrahedra\n", out.c_str(), n, m);
  return 0;
}
