// What the fuzz targets share: the input as text or as a file, and the one rule they check.
//
// The rule (issue 13): any input gives a valid scene or a clear error naming the key, file or
// field: a ConfigError, or false with a reason. Any other exception, a crash, a sanitizer report,
// a hang (libFuzzer -timeout) or an unbounded allocation (-rss_limit_mb, -malloc_limit_mb) is a
// finding. A scene that loads is also built and stepped when it is small enough for the fuzzer's
// pace (kMaxSteppedParticles, kMaxSteppedPasses): building is where sizes turn into allocations.
// A valid scene of a million particles or of 1000 x 1000 passes per step is slow, not wrong; the
// fuzzer would report it as a hang.
#pragma once

#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <fstream>
#include <string>
#include <typeinfo>

#include "pbd_cloth/sim/simulation.h"

namespace pbd_cloth {
namespace fuzz {

constexpr int kMaxSteppedParticles = 2000;
constexpr int kMaxSteppedPasses = 200;  // substeps x iterations

// An exception that escapes a target is a finding, and its input must be kept to replay it. It
// ends the process through std::terminate and abort(), and run_fuzz leaves SIGABRT to the
// sanitizers (-handle_abrt=0: assimp may abort in the mesh reader's child process, which reports
// that as a ConfigError), so libFuzzer would not write the input out. This handler names the
// exception and traps instead: libFuzzer handles SIGILL, writes the input to the artifacts
// directory and reports a deadly signal. (The reader's child catches every exception itself.)
[[noreturn]] inline void reportUncaughtException() {
  try {
    if (std::current_exception()) std::rethrow_exception(std::current_exception());
    std::fprintf(stderr, "fuzz: std::terminate without an exception\n");
  } catch (const std::exception& e) {
    std::fprintf(stderr, "fuzz: uncaught exception %s: %s\n", typeid(e).name(), e.what());
  } catch (...) {
    std::fprintf(stderr, "fuzz: uncaught exception of a type not derived from std::exception\n");
  }
  __builtin_trap();
}
inline const std::terminate_handler kPreviousTerminateHandler =
    std::set_terminate(reportUncaughtException);

inline std::string text(const std::uint8_t* data, std::size_t size) {
  return std::string(reinterpret_cast<const char*>(data), size);
}

// The input written to a file of its own (one per process), with the given extension.
inline std::string writeFile(const std::uint8_t* data, std::size_t size, const std::string& ext) {
  const std::string path = "/tmp/pbd_cloth_fuzz_" + std::to_string(::getpid()) + "." + ext;
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  return path;
}

// Builds and steps a scene that loaded (and so passed validate()). It must not throw: validate()
// promised that the scene is good.
inline void buildAndStep(const SceneConfig& scene, int steps = 1) {
  const long long particles =
      scene.cloth.mesh_data ? 0 : static_cast<long long>(scene.cloth.rows) * scene.cloth.cols;
  if (particles + scene.granular.count > kMaxSteppedParticles) return;
  if (static_cast<long long>(scene.solver.substeps) * scene.solver.iterations > kMaxSteppedPasses) {
    return;
  }
  Simulation sim(scene);
  for (int k = 0; k < steps; ++k) sim.step();
}

}  // namespace fuzz
}  // namespace pbd_cloth
