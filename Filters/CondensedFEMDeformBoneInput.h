// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// CondensedFEMDeform's bone, taken in one pass per update: `update` stamps the bone's structure
// once, validates the bone once (in full when its structure changed, else only the values an edit
// changes: points and Displacement), computes the undeformed bone (points minus Displacement) once,
// and answers what changed: the structure, the values, and whether the contact built from it still
// holds. The steps after it (contact, node sets, solve) ask it instead of looking at the bone
// again.
//
// The structure is the point count, the cells and the arrays ROIMask, SegmentId, Sliding and
// Released. It is identified by VTK modification times and, when they differ, by its bytes: an
// edit through Osteotomy, Append Geometry or several Bone connections hands over new arrays with
// the same values. The undeformed points are compared by value with a tolerance relative to the
// bone's size, because an edit moves points and Displacement together and their difference may
// change by rounding. Private to FacePlan::Filters.
#include "FacePlanDataStamp.h"

#include "Common/Status.h"

#include <vector>

class vtkPointSet;

namespace faceplan {
namespace fem_filter {

class BoneInput {
public:
  // Validates `bone` (a bone without cells, points or a valid Displacement is an error) for a
  // contact made on the tissue of `tissueGeneration` with these distances.
  Status update(vtkPointSet* bone, unsigned long tissueGeneration, double contactDistance,
                double releaseDistance);
  // What changed since the last successful update: the structure (cells, point count, ROIMask,
  // SegmentId, Sliding, Released). The values (points, Displacement) are new at every update.
  bool structureChanged() const { return structureChanged_; }
  // Whether the contact must be (re)built: the tissue, a distance, the structure or the
  // undeformed points differ from those of the last `contactBuilt`, or none was built yet.
  bool contactChanged() const { return contactChanged_; }
  // The undeformed bone of the last update (3 doubles per point).
  const std::vector<double>& undeformed() const { return undeformed_; }
  // Records this update's bone as the one the contact was built from; `contactLost` after a failed
  // build, so that the next update builds again.
  void contactBuilt();
  void contactLost() { haveContact_ = false; }

private:
  static constexpr const char* kStructureArrays[] = {"ROIMask", "SegmentId", "Sliding", "Released"};
  static DataStamp StructureStampOf(vtkPointSet* bone);
  // The structure's bytes: point count, cells (a polydata's raw offsets and connectivity, else the
  // cells one by one) and the structure arrays with their type and shape.
  static void StructureSignature(vtkPointSet* bone, std::vector<unsigned char>& out);
  bool sameUndeformed() const;

  // This update's bone.
  DataStamp stamp_;
  std::vector<unsigned char> signature_;
  bool haveSignature_ = false; // computed lazily: only when a stamp differs
  std::vector<double> undeformed_;
  unsigned long tissue_ = 0;
  double contactDistance_ = -1.0, releaseDistance_ = -1.0;
  bool structureChanged_ = true, contactChanged_ = true;

  // The last validated structure.
  bool validated_ = false;
  DataStamp validatedStamp_;
  std::vector<unsigned char> validatedSignature_;

  // The bone the contact was built from.
  bool haveContact_ = false;
  DataStamp contactStamp_;
  std::vector<unsigned char> contactSignature_;
  std::vector<double> contactUndeformed_;
  unsigned long contactTissue_ = 0;
  double contactDistanceBuilt_ = -1.0, releaseDistanceBuilt_ = -1.0;

  const std::vector<unsigned char>& signature(vtkPointSet* bone);
};

} // namespace fem_filter
} // namespace faceplan
