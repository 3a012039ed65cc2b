// A scene's rope (config/rope_config.h).
#include "pbd_cloth/config/rope_config.h"

namespace pbd_cloth {

Vec3Array RopeConfig::restPoints() const {
  if (!points.empty()) return points;
  Vec3Array out;
  if (segments < 1) return out;
  for (int i = 0; i <= segments; ++i) {
    out.push_back(start + (end - start) * (static_cast<double>(i) / segments));
  }
  return out;
}

}  // namespace pbd_cloth
