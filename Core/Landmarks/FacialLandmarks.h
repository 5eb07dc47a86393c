// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Facial landmarks by their standard definitions (Farkas's soft-tissue anthropometry; Holdaway's
// and Legan's cephalometry), found on planar sections of the pre-operative skin and bone, and the
// landmarks' movement in a reference frame. VTK-free: the filter (Filters/vtkFacialLandmarks) cuts
// the surfaces with VTK and hands the sections' segments here.
//
// Sections are read through their anterior envelope: along a height (or lateral) axis sampled at
// a fixed step, the most anterior point of the section at each sample. Profile landmarks are the
// envelope's peaks (most anterior points), notches and concavities (the point deepest behind the
// chord between two neighbouring landmarks), in the order the face has them from the nose down:
//   Pronasale: the most anterior point of the midline profile.
//   LabraleSuperius, LabraleInferius, SoftTissuePogonion: the first three peaks below pronasale
//     (peaks closer than 0.25 % of the profile's height to the dip between them are one peak).
//   Subnasale: the deepest point between Pronasale and LabraleSuperius.
//   Stomion: the most posterior point of the envelope between the lips.
//   SoftTissueB: the deepest point between LabraleInferius and SoftTissuePogonion.
//   SoftTissueMenton: the point of the skin section's lower outline vertically below bony Menton.
//   CheilionRight/Left: the deepest point of the horizontal section at Stomion's height, each side,
//     behind the chord from the lip's most anterior point past the fissure's notch at the midline
//     (more than 5 % of the profile's height to the side) to where the section lies 10 % of the
//     profile's height behind Stomion (the mouth's corner, where lip meets cheek).
//     Without a concavity (a coarse mesh), the point where the section has receded half as far
//     (with a note).
//   AlarBaseRight/Left: the same on the horizontal section a quarter of the way from Subnasale up
//   to
//     Pronasale, the chord from the section's most anterior point (the alar-facial groove).
// Bone, on the midline section, split at Stomion's height (the occlusal level):
//   UpperIncisorTip: the lowest point of the bone's envelope above it; LowerIncisorTip: the highest
//     below it.
//   ANS: the top of the anterior contour followed up from the upper incisor (where it ends or
//     steps back by more than 3 % of the profile's height or twice the section's median segment:
//     the piriform aperture).
//   APoint: the deepest point between ANS and UpperIncisorTip (on a convex maxilla, a third of the
//     way from ANS down to the incisor, with a note).
//   Pogonion: the most anterior point of the lower half of the anterior contour followed down from
//     the lower incisor; Menton: that contour's lowest point; BPoint: the deepest point between
//     LowerIncisorTip and Pogonion.
#include "Common/Status.h"

#include <Eigen/Core>

#include <array>
#include <string>
#include <vector>

namespace faceplan {
namespace landmarks {

enum class Landmark : int {
  Pronasale,
  Subnasale,
  AlarBaseRight,
  AlarBaseLeft,
  LabraleSuperius,
  Stomion,
  LabraleInferius,
  CheilionRight,
  CheilionLeft,
  SoftTissueB,
  SoftTissuePogonion,
  SoftTissueMenton,
  ANS,
  APoint,
  UpperIncisorTip,
  LowerIncisorTip,
  BPoint,
  Pogonion,
  Menton,
};
constexpr int kLandmarkCount = 19;

std::string LandmarkName(Landmark landmark);
bool IsSkinLandmark(Landmark landmark);
// The bony landmark whose movement a skin landmark's ratio is taken against (the landmark itself
// for a bony one).
Landmark PairedBone(Landmark landmark);

// The reference frame: the midsagittal plane (through `origin`, normal `lateral`), `anterior` out
// of the face and `superior` up, both in the plane. Unit, orthogonal.
struct Frame {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  Eigen::Vector3d anterior = -Eigen::Vector3d::UnitX();
  Eigen::Vector3d superior = Eigen::Vector3d::UnitZ();
  Eigen::Vector3d lateral = Eigen::Vector3d::UnitY();
};

// The model-axes frame: the midsagittal plane as given, anterior and superior the given directions
// projected into it. Fails on non-finite values, a zero normal or direction, or directions that are
// (nearly) parallel to each other or to the plane's normal.
Status ModelAxesFrame(const Eigen::Vector3d& planeOrigin, const Eigen::Vector3d& planeNormal,
                      const Eigen::Vector3d& anteriorHint, const Eigen::Vector3d& superiorHint,
                      Frame& frame);

// The Frankfort-horizontal frame: superior is the normal of the plane through both porions and the
// orbitale (oriented along `superiorHint`), anterior points from the porions' midpoint to the
// orbitale within that plane; the midsagittal plane passes through the porions' midpoint, normal to
// anterior and superior. Fails on non-finite or collinear points.
Status FrankfortFrame(const Eigen::Vector3d& porionRight, const Eigen::Vector3d& porionLeft,
                      const Eigen::Vector3d& orbitale, const Eigen::Vector3d& superiorHint,
                      Frame& frame);

// Segment end points of a planar section, two per segment.
using Segments = std::vector<Eigen::Vector3d>;

// Where the landmarks are (pre-operative positions) and why one was not found.
struct Placement {
  std::array<bool, kLandmarkCount> found{};
  std::array<Eigen::Vector3d, kLandmarkCount> position{};
  std::array<std::string, kLandmarkCount> note{};
  double profileHeight = 0.0; // the skin profile's height: the scale of the relative rules
  bool has(Landmark l) const { return found[static_cast<int>(l)]; }
  const Eigen::Vector3d& at(Landmark l) const { return position[static_cast<int>(l)]; }
  void set(Landmark l, const Eigen::Vector3d& x);
  void miss(Landmark l, const std::string& why);
};

// The midline skin landmarks (all but the cheilions, alar bases and SoftTissueMenton) from the
// skin's midsagittal section. Landmarks it cannot find get a note.
void PlaceMidlineSkin(const Segments& skinMidline, const Frame& frame, Placement& placement);

// The bony landmarks from the bone's midsagittal section; needs Stomion (the occlusal level) and
// Pronasale (the window's top).
void PlaceMidlineBone(const Segments& boneMidline, const Frame& frame, Placement& placement);

// SoftTissueMenton from the skin's midsagittal section; needs Menton and SoftTissuePogonion.
void PlaceSkinMenton(const Segments& skinMidline, const Frame& frame, Placement& placement);

// A pair of lateral landmarks (CheilionRight/Left or AlarBaseRight/Left) on the skin's horizontal
// section through `level` (Stomion; the alar level). Right is the side of -lateral. With
// `beyondNotch` (the cheilions) the chord starts past the oral fissure's notch at the midline.
void PlaceLateralPair(const Segments& horizontal, const Frame& frame, const Eigen::Vector3d& level,
                      Landmark right, Landmark left, bool beyondNotch, Placement& placement);

// The height of the alar-base section: a quarter of the way from Subnasale up to Pronasale.
Eigen::Vector3d AlarLevel(const Placement& placement);

} // namespace landmarks
} // namespace faceplan
