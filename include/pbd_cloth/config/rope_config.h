// A rope or cable of the scene (`ropes:`, a list): a Cosserat rod (model/rod.h) along a polyline.
#pragma once

#include <string>
#include <vector>

#include "pbd_cloth/geometry/vector_types.h"

namespace pbd_cloth {

struct RopeConfig {
  std::string name;  // ropes[i].name, unique among the scene's names
  // ropes[i].points: where the rope's particles start, [[x y z], ...] (at least 2), each segment
  // as long as placed; or, when empty, ropes[i].start / end / segments: a straight rope of
  // `segments` equal segments. At rest a rope is straight (it keeps no bend it starts with).
  Vec3Array points;
  Vec3 start = Vec3::Zero();
  Vec3 end = Vec3(1.0, 0.0, 0.0);
  int segments = 20;
  double radius = 0.005;             // m
  double density = 1000.0;           // kg/m^3
  double young_modulus = 1e7;        // Pa: stretch EA and bending EI = E pi r^4 / 4
  double shear_modulus = 4e6;        // Pa: shear GA and twist GJ = G pi r^4 / 2
  double stretch_compliance = -1.0;  // m/N per unit length; 0 = inextensible; < 0: from E and G
  std::vector<int> pinned;  // the rope's own particle indices (0 .. segments) held in place

  // The particles where the rope starts, from points or start/end/segments.
  Vec3Array restPoints() const;
};

}  // namespace pbd_cloth
