// Cloth meshes as OBJ text for the core tests, and writing them where a scene can load them.
#pragma once

#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>

namespace pbd_cloth {
namespace test {

// Writes `text` to a file of that name in the test's temporary directory; returns its path.
inline std::string writeObj(const std::string& name, const std::string& text) {
  const std::string path = (std::filesystem::temp_directory_path() / name).string();
  std::ofstream(path) << text;
  return path;
}

// A square of n x n particles at pitch s in the grid's layout (particle r * n + c at
// (c s, -r s, 0)); interior vertices moved by up to `jitter` s, every cell split along the
// other diagonal than the grid's checkerboard where `flip` says so.
inline std::string squareObj(int n, double s, double jitter, unsigned seed) {
  std::mt19937 random(seed);
  std::uniform_real_distribution<double> offset(-jitter, jitter);
  std::ostringstream obj;
  obj.precision(17);
  for (int r = 0; r < n; ++r) {
    for (int c = 0; c < n; ++c) {
      const bool interior = r > 0 && c > 0 && r + 1 < n && c + 1 < n;
      const double dx = interior ? offset(random) : 0.0, dy = interior ? offset(random) : 0.0;
      obj << "v " << (c + dx) * s << " " << -(r + dy) * s << " 0\n";
    }
  }
  std::bernoulli_distribution flip(0.5);
  for (int r = 0; r + 1 < n; ++r) {
    for (int c = 0; c + 1 < n; ++c) {
      const int a = r * n + c + 1, b = a + 1, d = a + n, e = d + 1;  // 1-based
      if (flip(random)) {
        obj << "f " << a << " " << d << " " << e << "\nf " << a << " " << e << " " << b << "\n";
      } else {
        obj << "f " << a << " " << d << " " << b << "\nf " << b << " " << d << " " << e << "\n";
      }
    }
  }
  return obj.str();
}

}  // namespace test
}  // namespace pbd_cloth
