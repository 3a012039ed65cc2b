#include "pbd_cloth/parallel/cpu_features.h"

namespace pbd_cloth {

#if defined(__x86_64__) && defined(__GNUC__)
bool cpuHasAvx2() {
  static const bool has = __builtin_cpu_supports("avx2");
  return has;
}

bool cpuHasAvx512F() {
  static const bool has = __builtin_cpu_supports("avx512f");
  return has;
}

bool cpuHasAvx512Vl() {
  static const bool has = __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vl");
  return has;
}
#else
bool cpuHasAvx2() { return false; }
bool cpuHasAvx512F() { return false; }
bool cpuHasAvx512Vl() { return false; }
#endif

}  // namespace pbd_cloth
