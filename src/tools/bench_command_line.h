// The command line that cloth_bench and bullet_cloth_bench share: both take the same options,
// read the scene the same way, write the same --csv rows and print the same key=value line, so
// the charts compare the two on equal terms. Header-only: the two tools are its only users.
#pragma once

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <iostream>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "pbd_cloth/config/scene_config.h"
#include "pbd_cloth/scene/scene_yaml.h"
#include "pbd_cloth/sim/metrics.h"

namespace pbd_cloth {
namespace bench {

// A bad command line: exit status 2, like a bad scene key.
struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

inline double parseNumber(const std::string& option, const std::string& text) {
  std::size_t used = 0;
  double value = std::numeric_limits<double>::quiet_NaN();
  try {
    value = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != text.size()) {
    throw UsageError(option + ": expected a number, got '" + text + "'");
  }
  return value;
}

inline int parseCount(const std::string& option, const std::string& text, int low, int high) {
  const double value = parseNumber(option, text);
  if (!(value >= low && value <= high && value == std::floor(value))) {
    throw UsageError(option + ": must be an integer in [" + std::to_string(low) + ", " +
                     std::to_string(high) + "], got " + text);
  }
  return static_cast<int>(value);
}

// The options both tools take.
struct CommonOptions {
  std::string config;
  double duration = -1.0;
  std::vector<std::string> overrides;  // --set key=value, in order
  std::string csv;
  std::string positions;
  std::string mesh;
  int sample_every = 0;  // 0: by scene size
  bool quiet = false;
};

using NextValue = std::function<std::string()>;

// Calls handle(option, next) for every option of argv, where next() returns the option's value
// (from --option=value or the following argument). handle returns false for an option it does
// not know, which is then an error.
inline void forEachOption(int argc, char** argv,
                          const std::function<bool(const std::string&, const NextValue&)>& handle) {
  const std::vector<std::string> args(argv + 1, argv + argc);
  for (std::size_t k = 0; k < args.size(); ++k) {
    std::string option = args[k];
    std::string value;
    bool has_value = false;
    // --option=value is accepted too; the first '=' splits, so --set=a.b=1 works.
    const std::size_t equals = option.find('=');
    if (option.rfind("--", 0) == 0 && equals != std::string::npos) {
      value = option.substr(equals + 1);
      option = option.substr(0, equals);
      has_value = true;
    }
    const NextValue next = [&]() -> std::string {
      if (has_value) return value;
      if (k + 1 >= args.size()) throw UsageError(option + " needs a value");
      return args[++k];
    };
    if (!handle(option, next)) throw UsageError("unknown argument '" + args[k] + "'");
  }
}

// Takes one of the common options; false when `option` is not one of them.
inline bool parseCommonOption(const std::string& option, const NextValue& next,
                              CommonOptions& options) {
  if (option == "--quiet") {
    options.quiet = true;
  } else if (option == "--config") {
    options.config = next();
  } else if (option == "--duration") {
    const std::string text = next();
    options.duration = parseNumber(option, text);
    if (!std::isfinite(options.duration) || options.duration < 0.0) {
      throw UsageError("--duration: must be a finite time >= 0 (s), got " + text);
    }
  } else if (option == "--set") {
    options.overrides.push_back(next());
  } else if (option == "--csv") {
    options.csv = next();
  } else if (option == "--positions") {
    options.positions = next();
  } else if (option == "--mesh") {
    options.mesh = next();
  } else if (option == "--sample-every") {
    options.sample_every = parseCount(option, next(), 1, 1000000000);
  } else {
    return false;
  }
  return true;
}

inline void requireCommonOptions(const CommonOptions& options) {
  if (options.config.empty()) throw UsageError("--config <scene.yaml> is required");
  if (options.duration < 0.0) throw UsageError("--duration <s> is required");
}

// Opened before the run so that a bad path fails in a second, not after a long run.
inline std::ofstream openOutput(const std::string& option, const std::string& path) {
  std::ofstream out;
  if (path.empty()) return out;
  out.open(path, std::ios::trunc);
  if (!out) throw UsageError(option + ": cannot write '" + path + "'");
  // Exact doubles: files of two runs can be compared bit for bit (determinism checks).
  out.precision(std::numeric_limits<double>::max_digits10);
  return out;
}

inline void finishOutput(std::ofstream& out, const std::string& path) {
  if (!out.is_open()) return;
  out.close();
  if (!out) throw std::runtime_error("writing '" + path + "' failed");
}

// The scene of --config with every --set applied in order; the reader's warnings go to stderr.
inline SceneConfig loadScene(const CommonOptions& options) {
  YAML::Node root = loadSceneYaml(options.config);
  for (const std::string& assignment : options.overrides) applyOverride(root, assignment);
  SceneConfig scene = sceneFromYaml(root, sceneFileDirectory(options.config));
  for (const std::string& warning : scene.load_warnings) {
    std::fprintf(stderr, "warning: %s\n", warning.c_str());
  }
  return scene;
}

// --csv: one row per metric sample, under this header. A tool with columns of its own appends
// them after these (more_columns: ",name,..."; cloth_bench's substeps_run,target_met), and each
// row then ends with their values (more_values: ",value,...").
inline void writeCsvHeader(std::ofstream& csv, const std::string& more_columns = "") {
  if (csv.is_open()) {
    csv << "t,max_strain,mean_strain,energy,max_penetration,structural_max_strain" << more_columns
        << '\n';
  }
}

inline void writeCsvRow(std::ofstream& csv, double t, const Metrics& m,
                        const std::string& more_values = "") {
  if (!csv.is_open()) return;
  csv << t << ',' << m.max_strain << ',' << m.mean_strain << ',' << m.energy << ','
      << m.max_penetration << ',' << m.structural_max_strain << more_values << '\n';
}

// The largest strain of the structural links over the run's last second: the median of its
// metric samples (last_second_median_structural_max_strain). The final instant alone swings
// between neighbouring settings where a cloth still whips (doc/journal.md, "Target 2, no longer on
// its edge": on its edge in strain: 1.01 % at 120 substeps, 2.39 % at 124, 0.999 % at 128); the
// median over a second is the steady reading beside it. The samples from step `from_step` on count:
// the last round(step_rate) steps of the run, or every step after the start of a shorter run.
class LastSecondStrain {
 public:
  LastSecondStrain(long long steps, double step_rate, int sample_every)
      : from_step_(std::max(1LL, steps - std::llround(step_rate))) {
    samples_.reserve(
        static_cast<std::size_t>((steps - from_step_) / std::max(1, sample_every) + 2));
  }
  // A metric sample taken after `step` steps.
  void add(long long step, const Metrics& m) {
    if (step < from_step_) return;
    // A blown-up cloth has no steady reading: its state is not finite (then its strain can read
    // 0, a NaN comparing false), or its strain is not (and a NaN would break the sort's order).
    if (!m.finite || !std::isfinite(m.structural_max_strain)) diverged_ = true;
    samples_.push_back(m.structural_max_strain);
  }
  // The median of the samples (the mean of the two middle ones for an even count); NaN if none,
  // or if one was not finite.
  double median() const {
    if (samples_.empty() || diverged_) return std::numeric_limits<double>::quiet_NaN();
    std::vector<double> sorted = samples_;
    std::sort(sorted.begin(), sorted.end());
    const std::size_t n = sorted.size();
    return n % 2 == 1 ? sorted[n / 2] : 0.5 * (sorted[n / 2 - 1] + sorted[n / 2]);
  }

 private:
  long long from_step_;
  std::vector<double> samples_;
  bool diverged_ = false;
};

// The structural strain of every step of the run's last second of simulated time (the last
// round(step_rate) steps, or every step of a shorter run), max and mean, and their medians
// (median_structural_max_strain_last_1s, median_structural_mean_strain_last_1s). Unlike
// LastSecondStrain it reads every step, whatever --sample-every says: the structural strain costs
// a pass over the links, not the self-intersection count of a metric sample. A cloth that blows up
// inside that second has no median (NaN), as one without steps there.
class LastSecondStepStrain {
 public:
  LastSecondStepStrain(long long steps, double step_rate)
      : from_step_(std::max(1LL, steps - std::llround(step_rate))) {
    const std::size_t room = static_cast<std::size_t>(std::max(0LL, steps - from_step_ + 1));
    max_.reserve(room);
    mean_.reserve(room);
  }
  // Whether the state after `step` steps is one of the last second's.
  bool counts(long long step) const { return step >= from_step_; }
  void add(double max_strain, double mean_strain) {
    if (!std::isfinite(max_strain) || !std::isfinite(mean_strain)) diverged_ = true;
    max_.push_back(max_strain);
    mean_.push_back(mean_strain);
  }
  double medianMax() const { return median(max_); }
  double medianMean() const { return median(mean_); }

 private:
  double median(const std::vector<double>& values) const {
    if (values.empty() || diverged_) return std::numeric_limits<double>::quiet_NaN();
    std::vector<double> sorted = values;
    std::sort(sorted.begin(), sorted.end());
    const std::size_t n = sorted.size();
    return n % 2 == 1 ? sorted[n / 2] : 0.5 * (sorted[n / 2 - 1] + sorted[n / 2]);
  }
  long long from_step_;
  std::vector<double> max_, mean_;
  bool diverged_ = false;
};

// main() of both tools: the exit status of run(), or what it threw as a message that names the
// tool: 2 for a bad command line or scene key, 1 for anything else.
template <typename Run>
int runTool(const char* tool, Run&& run) {
  try {
    return run();
  } catch (const UsageError& e) {
    std::cerr << tool << ": " << e.what() << "\n(" << tool << " --help lists the options)\n";
    return 2;
  } catch (const ConfigError& e) {
    std::cerr << tool << ": " << e.what() << '\n';
    return 2;
  } catch (const std::exception& e) {
    std::cerr << tool << ": " << e.what() << '\n';
    return 1;
  }
}

}  // namespace bench
}  // namespace pbd_cloth
