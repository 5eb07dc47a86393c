// SPDX-License-Identifier: BSD-3-Clause
#include "Landmarks/FacialLandmarks.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>

namespace faceplan {
namespace landmarks {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// The most anterior point of a section at each sample of an axis.
struct Envelope {
  double u0 = 0.0, step = 1.0;
  std::vector<double> v;              // anterior coordinate; NaN where the section has no point
  std::vector<Eigen::Vector3d> point; // the section's point there
  int size() const { return static_cast<int>(v.size()); }
  bool ok(int k) const { return k >= 0 && k < size() && std::isfinite(v[k]); }
  double u(int k) const { return u0 + step * k; }
  double span() const { return step * std::max(0, size() - 1); }
};

// Samples `axis` at `count` points over the section's extent; at each, the largest `front`
// coordinate where a segment crosses.
Envelope AnteriorEnvelope(const Segments& segments, const Eigen::Vector3d& axis,
                          const Eigen::Vector3d& front, int count = 2000) {
  Envelope e;
  if (segments.size() < 2)
    return e;
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (const Eigen::Vector3d& p : segments) {
    lo = std::min(lo, axis.dot(p));
    hi = std::max(hi, axis.dot(p));
  }
  if (!(hi > lo))
    return e;
  e.u0 = lo;
  e.step = (hi - lo) / (count - 1);
  e.v.assign(static_cast<std::size_t>(count), kNaN);
  e.point.assign(static_cast<std::size_t>(count), Eigen::Vector3d::Zero());
  for (std::size_t i = 0; i + 1 < segments.size(); i += 2) {
    const Eigen::Vector3d &p = segments[i], &q = segments[i + 1];
    double up = axis.dot(p), uq = axis.dot(q);
    const int k0 = static_cast<int>(std::ceil((std::min(up, uq) - lo) / e.step));
    const int k1 = static_cast<int>(std::floor((std::max(up, uq) - lo) / e.step));
    for (int k = std::max(0, k0); k <= std::min(count - 1, k1); ++k) {
      const double t = uq != up ? (e.u(k) - up) / (uq - up) : 0.0;
      const Eigen::Vector3d x = p + std::clamp(t, 0.0, 1.0) * (q - p);
      const double v = front.dot(x);
      if (!(v <= e.v[k])) { // also true for NaN
        e.v[k] = v;
        e.point[k] = x;
      }
    }
  }
  return e;
}

int ArgMax(const Envelope& e, int from, int to) {
  int best = -1;
  for (int k = std::max(0, from); k <= std::min(e.size() - 1, to); ++k)
    if (e.ok(k) && (best < 0 || e.v[k] > e.v[best]))
      best = k;
  return best;
}

int ArgMin(const Envelope& e, int from, int to) {
  int best = -1;
  for (int k = std::max(0, from); k <= std::min(e.size() - 1, to); ++k)
    if (e.ok(k) && (best < 0 || e.v[k] < e.v[best]))
      best = k;
  return best;
}

// The sample deepest behind the chord between samples a and b (exclusive); -1 if none lies
// behind it.
int Deepest(const Envelope& e, int a, int b) {
  if (a > b)
    std::swap(a, b);
  if (!e.ok(a) || !e.ok(b))
    return -1;
  int best = -1;
  double depth = 0.0;
  for (int k = a + 1; k < b; ++k) {
    if (!e.ok(k))
      continue;
    const double line = e.v[a] + (e.v[b] - e.v[a]) * (k - a) / double(b - a);
    if (line - e.v[k] > depth) {
      depth = line - e.v[k];
      best = k;
    }
  }
  return best;
}

} // namespace

std::string LandmarkName(Landmark l) {
  static const char* names[kLandmarkCount] = {"Pronasale",
                                              "Subnasale",
                                              "AlarBaseRight",
                                              "AlarBaseLeft",
                                              "LabraleSuperius",
                                              "Stomion",
                                              "LabraleInferius",
                                              "CheilionRight",
                                              "CheilionLeft",
                                              "SoftTissueB",
                                              "SoftTissuePogonion",
                                              "SoftTissueMenton",
                                              "ANS",
                                              "APoint",
                                              "UpperIncisorTip",
                                              "LowerIncisorTip",
                                              "BPoint",
                                              "Pogonion",
                                              "Menton"};
  const int i = static_cast<int>(l);
  return i >= 0 && i < kLandmarkCount ? names[i] : "";
}

bool IsSkinLandmark(Landmark l) {
  return static_cast<int>(l) < static_cast<int>(Landmark::ANS);
}

Landmark PairedBone(Landmark l) {
  switch (l) {
  case Landmark::Pronasale:
    return Landmark::ANS;
  case Landmark::Subnasale:
  case Landmark::AlarBaseRight:
  case Landmark::AlarBaseLeft:
    return Landmark::APoint;
  case Landmark::LabraleSuperius:
  case Landmark::Stomion:
  case Landmark::CheilionRight:
  case Landmark::CheilionLeft:
    return Landmark::UpperIncisorTip;
  case Landmark::LabraleInferius:
    return Landmark::LowerIncisorTip;
  case Landmark::SoftTissueB:
    return Landmark::BPoint;
  case Landmark::SoftTissuePogonion:
    return Landmark::Pogonion;
  case Landmark::SoftTissueMenton:
    return Landmark::Menton;
  default:
    return l;
  }
}

void Placement::set(Landmark l, const Eigen::Vector3d& x) {
  found[static_cast<int>(l)] = true;
  position[static_cast<int>(l)] = x;
  note[static_cast<int>(l)].clear();
}

void Placement::miss(Landmark l, const std::string& why) {
  found[static_cast<int>(l)] = false;
  position[static_cast<int>(l)] = Eigen::Vector3d::Zero();
  note[static_cast<int>(l)] = why;
}

Status ModelAxesFrame(const Eigen::Vector3d& planeOrigin, const Eigen::Vector3d& planeNormal,
                      const Eigen::Vector3d& anteriorHint, const Eigen::Vector3d& superiorHint,
                      Frame& frame) {
  if (!planeOrigin.allFinite() || !planeNormal.allFinite() || !anteriorHint.allFinite() ||
      !superiorHint.allFinite())
    return Status::Error("the midsagittal plane or a frame direction is not finite");
  if (!(planeNormal.norm() > 0.0) || !(anteriorHint.norm() > 0.0) || !(superiorHint.norm() > 0.0))
    return Status::Error("the midsagittal plane's normal or a frame direction has zero length");
  const Eigen::Vector3d n = planeNormal.normalized();
  Eigen::Vector3d a = anteriorHint.normalized();
  a -= a.dot(n) * n;
  if (!(a.norm() > 0.17)) // within 10 degrees of the normal
    return Status::Error("the anterior direction is (nearly) normal to the midsagittal plane: the "
                         "frame is degenerate");
  a.normalize();
  Eigen::Vector3d s = superiorHint.normalized();
  s -= s.dot(n) * n + s.dot(a) * a;
  if (!(s.norm() > 0.17))
    return Status::Error("the superior direction is (nearly) parallel to the anterior direction "
                         "or the plane's normal: the frame is degenerate");
  frame.origin = planeOrigin;
  frame.anterior = a;
  frame.superior = s.normalized();
  frame.lateral = frame.superior.cross(frame.anterior); // right-handed: anterior, lateral, up
  return Status::Ok();
}

Status FrankfortFrame(const Eigen::Vector3d& porionRight, const Eigen::Vector3d& porionLeft,
                      const Eigen::Vector3d& orbitale, const Eigen::Vector3d& superiorHint,
                      Frame& frame) {
  if (!porionRight.allFinite() || !porionLeft.allFinite() || !orbitale.allFinite() ||
      !superiorHint.allFinite())
    return Status::Error("a Frankfort point or the superior direction is not finite");
  const Eigen::Vector3d mid = 0.5 * (porionRight + porionLeft);
  const Eigen::Vector3d across = porionLeft - porionRight, forward = orbitale - mid;
  Eigen::Vector3d up = across.cross(forward);
  const double scale = across.norm() * forward.norm();
  if (!(scale > 0.0) || !(up.norm() > 1e-3 * scale))
    return Status::Error("the porions and the orbitale are collinear or coincide: the Frankfort "
                         "plane is degenerate");
  up.normalize();
  if (up.dot(superiorHint) < 0.0)
    up = -up;
  Eigen::Vector3d a = forward - forward.dot(up) * up;
  a -= a.dot(across.normalized()) * across.normalized();
  if (!(a.norm() > 1e-3 * forward.norm()))
    return Status::Error(
        "the orbitale lies on the porions' line: the Frankfort frame is degenerate");
  frame.origin = mid;
  frame.anterior = a.normalized();
  frame.superior = up;
  frame.lateral = frame.superior.cross(frame.anterior);
  return Status::Ok();
}

void PlaceMidlineSkin(const Segments& skin, const Frame& f, Placement& p) {
  const Landmark all[] = {Landmark::Pronasale,         Landmark::Subnasale,
                          Landmark::LabraleSuperius,   Landmark::Stomion,
                          Landmark::LabraleInferius,   Landmark::SoftTissueB,
                          Landmark::SoftTissuePogonion};
  const Envelope e = AnteriorEnvelope(skin, f.superior, f.anterior);
  if (e.size() == 0) {
    for (Landmark l : all)
      p.miss(l, "the skin has no midsagittal section (is the midsagittal plane on the face?)");
    return;
  }
  p.profileHeight = e.span();
  const int prn = ArgMax(e, 0, e.size() - 1);
  p.set(Landmark::Pronasale, e.point[prn]);
  // Peaks below pronasale: samples at least as anterior as every sample within w of them.
  const int w = std::max(1, static_cast<int>(0.025 * e.size()));
  std::vector<int> peaks;
  for (int k = prn - w; k >= 0; --k) {
    if (!e.ok(k))
      continue;
    const int top = ArgMax(e, k - w, k + w);
    if (top == k && (peaks.empty() || peaks.back() - k > 1))
      peaks.push_back(k);
  }
  // Neighbouring peaks with no real dip between them are one.
  const double dip = 0.0025 * e.span();
  for (std::size_t i = 0; i + 1 < peaks.size();) {
    const int a = peaks[i], b = peaks[i + 1];
    const int low = ArgMin(e, b, a);
    if (std::min(e.v[a], e.v[b]) - e.v[low] < dip) {
      peaks[i] = e.v[a] >= e.v[b] ? a : b;
      peaks.erase(peaks.begin() + static_cast<long>(i) + 1);
    } else {
      ++i;
    }
  }
  const std::string few = "the profile below pronasale has fewer than three prominences (upper "
                          "lip, lower lip, chin)";
  if (peaks.size() < 3) {
    for (Landmark l : all)
      if (l != Landmark::Pronasale)
        p.miss(l, few);
    return;
  }
  const int ls = peaks[0], li = peaks[1], pog = peaks[2];
  p.set(Landmark::LabraleSuperius, e.point[ls]);
  p.set(Landmark::LabraleInferius, e.point[li]);
  p.set(Landmark::SoftTissuePogonion, e.point[pog]);
  p.set(Landmark::Stomion, e.point[ArgMin(e, li + 1, ls - 1)]);
  const int sn = Deepest(e, prn, ls);
  if (sn >= 0)
    p.set(Landmark::Subnasale, e.point[sn]);
  else
    p.miss(Landmark::Subnasale, "no concavity between pronasale and labrale superius");
  const int b = Deepest(e, li, pog);
  if (b >= 0)
    p.set(Landmark::SoftTissueB, e.point[b]);
  else
    p.miss(Landmark::SoftTissueB, "no concavity between labrale inferius and soft pogonion");
}

void PlaceMidlineBone(const Segments& bone, const Frame& f, Placement& p) {
  const Landmark all[] = {
      Landmark::ANS,    Landmark::APoint,   Landmark::UpperIncisorTip, Landmark::LowerIncisorTip,
      Landmark::BPoint, Landmark::Pogonion, Landmark::Menton};
  if (!p.has(Landmark::Stomion) || !p.has(Landmark::Pronasale)) {
    for (Landmark l : all)
      p.miss(l, "needs Stomion and Pronasale on the skin (the occlusal level and the window)");
    return;
  }
  Envelope e = AnteriorEnvelope(bone, f.superior, f.anterior);
  if (e.size() == 0) {
    for (Landmark l : all)
      p.miss(l, "the bone has no midsagittal section");
    return;
  }
  const double H = p.profileHeight > 0.0 ? p.profileHeight : e.span();
  const double occlusal = f.superior.dot(p.at(Landmark::Stomion));
  const double top = f.superior.dot(p.at(Landmark::Pronasale));
  auto index = [&](double u) { return static_cast<int>(std::floor((u - e.u0) / e.step)); };
  const int kOcc = index(occlusal), kTop = index(top);
  // A step back of the contour larger than 3 % of the face's height, or than twice the section's
  // median segment (a coarse mesh's facets), leaves the jaw's anterior surface.
  std::vector<double> lengths;
  for (std::size_t i = 0; i + 1 < bone.size(); i += 2)
    lengths.push_back((bone[i + 1] - bone[i]).norm());
  std::nth_element(lengths.begin(), lengths.begin() + static_cast<long>(lengths.size() / 2),
                   lengths.end());
  const double jump = std::max(0.03 * H, 2.0 * lengths[lengths.size() / 2]), reach = 0.1 * H;
  // Follows the anterior contour from `start` in direction `dir` while it does not step back by
  // more than `jump`, across gaps no longer than `jump` (where a coarse section has a hole);
  // returns the last sample.
  // Samples off the contour inside the run are dropped, so that the concavities and extremes
  // below see the contour only.
  auto follow = [&](int start, int dir) {
    int last = start;
    std::vector<int> gap;
    for (int k = start + dir; k >= 0 && k < e.size(); k += dir) {
      // A sample off the contour (none, or a posterior surface seen through a hole of the
      // section) is a gap.
      if (!e.ok(k) || std::abs(e.v[k] - e.v[last]) > jump) {
        if (std::abs(k - last) * e.step > jump)
          break;
        gap.push_back(k);
        continue;
      }
      for (int g : gap)
        e.v[g] = kNaN;
      gap.clear();
      last = k;
    }
    return last;
  };

  // Upper jaw: above the occlusal level, up to pronasale's height.
  const int upperFront = ArgMax(e, kOcc + 1, kTop);
  int uit = -1;
  for (int k = std::max(0, kOcc + 1); upperFront >= 0 && k <= std::min(kTop, e.size() - 1); ++k)
    if (e.ok(k) && e.v[k] >= e.v[upperFront] - reach) {
      uit = k;
      break;
    }
  if (uit < 0) {
    for (Landmark l : {Landmark::ANS, Landmark::APoint, Landmark::UpperIncisorTip})
      p.miss(l, "no bone between the occlusal level (stomion) and pronasale's height");
  } else {
    p.set(Landmark::UpperIncisorTip, e.point[uit]);
    const int ans = follow(uit, +1);
    if (ans - uit < 2) {
      p.miss(Landmark::ANS, "the maxilla's anterior contour has no height");
      p.miss(Landmark::APoint, "needs ANS");
    } else {
      p.set(Landmark::ANS, e.point[ans]);
      const int a = Deepest(e, uit, ans);
      if (a >= 0) {
        p.set(Landmark::APoint, e.point[a]);
      } else {
        // A convex anterior maxilla (no subspinale concavity): a third of the way from ANS down
        // to the incisor, where the concavity usually lies (over the central incisor's apex).
        p.set(Landmark::APoint, e.point[ans - (ans - uit) / 3]);
        p.note[static_cast<int>(Landmark::APoint)] =
            "no concavity below ANS: taken a third of the way from ANS to the incisor tip";
      }
    }
  }
  // Lower jaw: below the occlusal level.
  const int lowerFront = ArgMax(e, 0, kOcc - 1);
  int lit = -1;
  for (int k = std::min(kOcc - 1, e.size() - 1); lowerFront >= 0 && k >= 0; --k)
    if (e.ok(k) && e.v[k] >= e.v[lowerFront] - reach) {
      lit = k;
      break;
    }
  if (lit < 0) {
    for (Landmark l :
         {Landmark::LowerIncisorTip, Landmark::BPoint, Landmark::Pogonion, Landmark::Menton})
      p.miss(l, "no bone below the occlusal level (stomion)");
    return;
  }
  p.set(Landmark::LowerIncisorTip, e.point[lit]);
  const int me = follow(lit, -1);
  if (lit - me < 4) {
    for (Landmark l : {Landmark::BPoint, Landmark::Pogonion, Landmark::Menton})
      p.miss(l, "the mandible's anterior contour has no height");
    return;
  }
  p.set(Landmark::Menton, e.point[me]);
  const int pog = ArgMax(e, me, (me + lit) / 2);
  p.set(Landmark::Pogonion, e.point[pog]);
  const int b = Deepest(e, pog, lit);
  if (b >= 0)
    p.set(Landmark::BPoint, e.point[b]);
  else
    p.miss(Landmark::BPoint, "no concavity between the lower incisor and pogonion");
}

void PlaceSkinMenton(const Segments& skin, const Frame& f, Placement& p) {
  if (!p.has(Landmark::Menton) || !p.has(Landmark::SoftTissuePogonion)) {
    p.miss(Landmark::SoftTissueMenton, "needs Menton on the bone and SoftTissuePogonion");
    return;
  }
  // The lower outline: the lowest point of the section along the anterior axis; soft menton is
  // its point vertically below bony menton.
  const Envelope e = AnteriorEnvelope(skin, f.anterior, -f.superior);
  const double a = f.anterior.dot(p.at(Landmark::Menton));
  const int k = e.size() > 0 ? static_cast<int>(std::lround((a - e.u0) / e.step)) : -1;
  if (!e.ok(k) || -e.v[k] > f.superior.dot(p.at(Landmark::Menton)))
    p.miss(Landmark::SoftTissueMenton, "no skin below bony menton");
  else
    p.set(Landmark::SoftTissueMenton, e.point[k]);
}

void PlaceLateralPair(const Segments& horizontal, const Frame& f, const Eigen::Vector3d& level,
                      Landmark right, Landmark left, bool beyondNotch, Placement& p) {
  const Envelope e = AnteriorEnvelope(horizontal, f.lateral, f.anterior);
  if (e.size() == 0 || !(p.profileHeight > 0.0)) {
    p.miss(right, "the skin has no horizontal section at this height");
    p.miss(left, "the skin has no horizontal section at this height");
    return;
  }
  const double behind = 0.1 * p.profileHeight;
  const int centre = std::clamp(
      static_cast<int>(std::lround((f.lateral.dot(level) - e.u0) / e.step)), 0, e.size() - 1);
  for (int dir : {-1, +1}) {
    const Landmark l = dir < 0 ? right : left;
    // Outwards from the midline to where the section lies `behind` behind the level's point.
    const double v0 = f.anterior.dot(level);
    int end = -1;
    for (int k = centre; k >= 0 && k < e.size(); k += dir)
      if (e.ok(k) && e.v[k] <= v0 - behind) {
        end = k;
        break;
      }
    if (end < 0) {
      p.miss(l, "the horizontal section does not recede on this side");
      continue;
    }
    int front = dir < 0 ? ArgMax(e, end, centre) : ArgMax(e, centre, end);
    if (beyondNotch) {
      // Past the oral fissure's notch (or gap, where the section passes between the lips) at
      // the midline: the lip's most anterior point beyond 5 % of the profile's height from it.
      const int skip = static_cast<int>(0.05 * p.profileHeight / e.step);
      front = dir < 0 ? ArgMax(e, end, centre - skip) : ArgMax(e, centre + skip, end);
    }
    const int k = front >= 0 ? Deepest(e, front, end) : -1;
    if (k >= 0) {
      p.set(l, e.point[k]);
      continue;
    }
    // A convex section (a coarse mesh): where it has receded half-way to the chord's end.
    int half = -1;
    for (int j = centre; j >= 0 && j < e.size(); j += dir)
      if (e.ok(j) && e.v[j] <= v0 - 0.5 * behind) {
        half = j;
        break;
      }
    if (half < 0) {
      p.miss(l, "no concavity on the horizontal section on this side");
    } else {
      p.set(l, e.point[half]);
      p.note[static_cast<int>(l)] =
          "no concavity on this side: taken where the section has receded half-way";
    }
  }
}

Eigen::Vector3d AlarLevel(const Placement& p) {
  return p.at(Landmark::Subnasale) + 0.25 * (p.at(Landmark::Pronasale) - p.at(Landmark::Subnasale));
}

} // namespace landmarks
} // namespace faceplan
