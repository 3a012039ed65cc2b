#include "pbd_cloth/solver/solver_settings.h"

namespace pbd_cloth {

const char* toString(Method method) {
  switch (method) {
    case Method::kVerlet:
      return "verlet";
    case Method::kPbd:
      return "pbd";
    case Method::kXpbd:
      return "xpbd";
    case Method::kMassSpring:
      return "mass_spring";
  }
  return "unknown";
}

const char* toString(Ordering ordering) {
  switch (ordering) {
    case Ordering::kGaussSeidel:
      return "gauss_seidel";
    case Ordering::kJacobi:
      return "jacobi";
  }
  return "unknown";
}

}  // namespace pbd_cloth
