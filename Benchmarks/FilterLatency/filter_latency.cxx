// SPDX-License-Identifier: BSD-3-Clause
// Edit latency of the Condensed FEM Deform filter itself (the VTK algorithm ParaView's proxy runs),
// on the ~100k shell scene of Benchmarks/pipeline_latency.py, with a chosen backend. Made for GPU
// hosts without ParaView, where pvpython cannot run: it measures the filter's update with
// Backend = CUDA at ~100k cells with VTK alone. The pipeline is pipeline_latency.py's shell scene
// built from VTK classes: legacy reader -> the inner sphere's boundary (point array Layer = 0) ->
// vtkROIExtract (sphere over the pole) -> vtkBezierCut (a plane 5 mm into the cap) ->
// vtkCondensedFEMDeform (Surface output). After the first, precomputing update each edit moves the
// cut's plane by up to 0.25 mm; per edit it times vtkBezierCut::Update and
// vtkCondensedFEMDeform::Update (wall clock) and reads SolveTimeMs from the output. Fails if an
// edit starts a new precompute. Medians, as JSON with --json.
//   filter_latency --scene shell.vtk [--backend CPU|CUDA] [--edits 30] [--json out.json]
#include "vtkBezierCut.h"
#include "vtkCondensedFEMDeform.h"
#include "vtkROIExtract.h"

#include <vtkDataArray.h>
#include <vtkDataSetSurfaceFilter.h>
#include <vtkFieldData.h>
#include <vtkGeometryFilter.h>
#include <vtkNew.h>
#include <vtkPointSet.h>
#include <vtkSphere.h>
#include <vtkStringArray.h>
#include <vtkThreshold.h>
#include <vtkUnstructuredGrid.h>
#include <vtkUnstructuredGridReader.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

namespace {

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? NAN : v[v.size() / 2];
}

double Field(vtkDataObject* out, const char* name) {
  vtkDataArray* array = out ? out->GetFieldData()->GetArray(name) : nullptr;
  return array ? array->GetTuple1(0) : NAN;
}

std::string FieldText(vtkDataObject* out, const char* name) {
  auto* array =
      out ? vtkStringArray::SafeDownCast(out->GetFieldData()->GetAbstractArray(name)) : nullptr;
  return array && array->GetNumberOfValues() > 0 ? array->GetValue(0) : std::string("?");
}

void SetPlane(vtkBezierCut* cut, double z) { // pipeline_latency.py's plane cutting the pole's cap
  const double u[4][2] = {{-70, -70}, {-23, -70}, {23, -70}, {70, -70}};
  const double v[4][2] = {{-70, -70}, {-70, -23}, {-70, 23}, {-70, 70}};
  cut->SetNumberOfCurveUPoints(4);
  cut->SetNumberOfCurveVPoints(4);
  for (int i = 0; i < 4; ++i) {
    cut->SetCurveUPoint(i, u[i][0], u[i][1], z);
    cut->SetCurveVPoint(i, v[i][0], v[i][1], z);
  }
}

double Ms(std::chrono::steady_clock::time_point from, std::chrono::steady_clock::time_point to) {
  return std::chrono::duration<double, std::milli>(to - from).count();
}

} // namespace

int main(int argc, char** argv) {
  std::string scene, backend = "CPU", json;
  int edits = 30;
  for (int i = 1; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--scene"))
      scene = argv[i + 1];
    else if (!std::strcmp(argv[i], "--backend"))
      backend = argv[i + 1];
    else if (!std::strcmp(argv[i], "--edits"))
      edits = std::max(1, std::atoi(argv[i + 1]));
    else if (!std::strcmp(argv[i], "--json"))
      json = argv[i + 1];
    else {
      std::fprintf(stderr, "unknown option %s\n", argv[i]);
      return 2;
    }
  }
  if (scene.empty() || (backend != "CPU" && backend != "CUDA")) {
    std::fprintf(
        stderr,
        "usage: filter_latency --scene shell.vtk [--backend CPU|CUDA] [--edits N] [--json F]\n");
    return 2;
  }
  vtkNew<vtkUnstructuredGridReader> tissue;
  tissue->SetFileName(scene.c_str());
  tissue->Update();
  vtkNew<vtkDataSetSurfaceFilter> surface;
  surface->SetInputConnection(tissue->GetOutputPort());
  vtkNew<vtkThreshold> inner;
  inner->SetInputConnection(surface->GetOutputPort());
  inner->SetInputArrayToProcess(0, 0, 0, vtkDataObject::FIELD_ASSOCIATION_POINTS, "Layer");
  inner->SetLowerThreshold(0);
  inner->SetUpperThreshold(0);
  inner->SetAllScalars(true);
  vtkNew<vtkGeometryFilter> bone;
  bone->SetInputConnection(inner->GetOutputPort());
  vtkNew<vtkSphere> region;
  region->SetCenter(0.0, 0.0, 80.0); // the inner sphere's pole (radius 80 mm)
  region->SetRadius(50.0);
  vtkNew<vtkROIExtract> roi;
  roi->SetInputConnection(bone->GetOutputPort());
  roi->SetRegion(region);
  vtkNew<vtkBezierCut> cut;
  cut->SetInputConnection(roi->GetOutputPort());
  vtkNew<vtkCondensedFEMDeform> fem;
  fem->SetInputConnection(0, tissue->GetOutputPort());
  fem->SetBoneConnection(cut->GetOutputPort());
  fem->SetBackend(backend == "CUDA" ? vtkCondensedFEMDeform::BACKEND_CUDA
                                    : vtkCondensedFEMDeform::BACKEND_CPU);
  fem->SetOutputMode(vtkCondensedFEMDeform::SURFACE);
  fem->SetContactDistance(0.5);

  auto edit = [&](int k) { SetPlane(cut, 75.0 + 0.25 * ((k * 7) % 9 - 4) / 4.0); };
  edit(0);
  cut->Update();
  auto t0 = std::chrono::steady_clock::now();
  fem->Update();
  const double firstMs = Ms(t0, std::chrono::steady_clock::now());
  vtkDataObject* out = fem->GetOutputDataObject(0);
  const vtkIdType outputPoints =
      vtkPointSet::SafeDownCast(out) ? vtkPointSet::SafeDownCast(out)->GetNumberOfPoints() : 0;
  if (outputPoints == 0) {
    std::fprintf(stderr, "CondensedFEMDeform produced no output\n");
    return 1;
  }
  const std::string usedBackend = FieldText(out, "Backend");
  if (backend == "CUDA" && usedBackend.find("CUDA") == std::string::npos) {
    std::fprintf(stderr, "asked for the CUDA backend, the filter ran on %s\n", usedBackend.c_str());
    return 1;
  }
  const int precomputes = fem->GetPrecomputeCount();
  std::vector<double> cutMs, femMs, solveMs, overheadMs;
  for (int k = 1; k <= edits; ++k) {
    edit(k);
    const auto a = std::chrono::steady_clock::now();
    cut->Update();
    const auto b = std::chrono::steady_clock::now();
    fem->Update();
    const auto c = std::chrono::steady_clock::now();
    cutMs.push_back(Ms(a, b));
    femMs.push_back(Ms(b, c));
    solveMs.push_back(Field(fem->GetOutputDataObject(0), "SolveTimeMs"));
    overheadMs.push_back(femMs.back() - solveMs.back());
  }
  if (fem->GetPrecomputeCount() != precomputes) {
    std::fprintf(stderr, "an edit of the cut started a new precompute\n");
    return 1;
  }
  std::printf(
      "shell (Surface output), backend %s (%s): tets %lld, first update %.1f ms | per edit (median "
      "of %d): "
      "CondensedFEMDeform update %.3f ms (p90 %.3f), SolveTimeMs %.3f, overhead %.3f; BezierCut "
      "%.3f ms\n",
      backend.c_str(), usedBackend.c_str(),
      static_cast<long long>(tissue->GetOutput()->GetNumberOfCells()), firstMs, edits,
      Median(femMs),
      [&] {
        std::vector<double> s = femMs;
        std::sort(s.begin(), s.end());
        return s[(s.size() - 1) * 9 / 10];
      }(),
      Median(solveMs), Median(overheadMs), Median(cutMs));
  if (!json.empty()) {
    std::ofstream j(json);
    j << "{\"backend\": \"" << backend << "\", \"backend_used\": \"" << usedBackend
      << "\", \"tets\": " << tissue->GetOutput()->GetNumberOfCells() << ", \"edits\": " << edits
      << ", \"first_update_ms\": " << firstMs << ", \"fem_update_ms_median\": " << Median(femMs)
      << ", \"solve_ms_median\": " << Median(solveMs)
      << ", \"overhead_ms_median\": " << Median(overheadMs)
      << ", \"bezier_cut_ms_median\": " << Median(cutMs) << "}\n";
  }
  return 0;
}
