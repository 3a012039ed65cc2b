// cloth_bench: runs a scene YAML offline (no ROS master) with the fixed step 1/step_rate and prints
// one line of key=value metrics, the same Simulation the node drives. See kUsage.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <fstream>
#include <iostream>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "bench_command_line.h"
#include "pbd_cloth/scene/scene_yaml.h"
#include "pbd_cloth/sensors/depth_camera.h"
#include "pbd_cloth/sim/simulation.h"

namespace {

const char kUsage[] =
    "Usage: cloth_bench --config <scene.yaml> --duration <s> [options]\n"
    "Runs the scene without ROS (from its initial state, or from --load-state) for\n"
    "round(duration * step_rate) steps of 1/step_rate s and prints\n"
    "one line of key=value metrics on stdout (wall_ms_per_step max_strain mean_strain\n"
    "max_penetration self_intersections energy finite steps sim_time iterations_per_step\n"
    "predict_ms (each substep's prediction, from the second substep on with the velocity update\n"
    "of the substep before, done in the same pass) collide_ms project_ms update_ms (the last\n"
    "substep's velocity update) contact_ms broad_phase_runs\n"
    "vertex_triangle_pairs edge_edge_pairs (self-collision candidates per step) search_window\n"
    "(substeps per contact search, mean over the steps) truncated_searches (self-collision\n"
    "searches of the run that stopped at their candidate budget: a cloth crushed into itself)\n"
    "local_searches (per step: searches for a few particles that left their bounds, alone)\n"
    "solo_steps (steps that solver.adaptive_threads ran on the calling thread alone)\n"
    "columns_steps (steps of links alone, run with the particles in columns: Solver::linksAlone)\n"
    "target_met_fraction (solver.target_max_strain / target_penetration: the fraction of the\n"
    "steps that met the targets; 1 without a target) mean_substeps (substeps run per step, every\n"
    "attempt of a step run again counted) redone_steps (steps a target ran again)\n"
    "worst_structural_max_strain (the largest structural max strain over every step of the run,\n"
    "whatever --sample-every says: <= a target means the target was met at every step)\n"
    "budget_exhausted_steps (steps that missed the target at solver.max_substeps: the budget\n"
    "did not allow it) worst_target_ratio_within_budget (the largest error over its target,\n"
    "max(strain / target_max_strain, penetration / target_penetration), over the other steps;\n"
    "0 without a target)\n"
    "controller_ms_per_step and controller_fraction (with a target: the controller's own work,\n"
    "timed here on the state of each step as the core does it: the structural strain measured\n"
    "once an attempt and the particles copied once an attempt, for the step's start and its\n"
    "redos; its mean per step, and over wall_ms_per_step; 0 without a target)\n"
    "method substeps\n"
    "iterations ...).\n"
    "Only the step calls are timed (cpu_ms_per_step: their processor time, which leaves out\n"
    "waiting for a core on a shared machine). max_strain, max_penetration and "
    "max_self_intersections are\n"
    "maxima over the run, sampled every step when the scene has <= 5000 particles and every 10th\n"
    "step otherwise (metrics are expensive on big scenes), and always at the last step; the other\n"
    "metrics are those of the final state; final_structural_max_strain and\n"
    "final_structural_mean_strain are its strain over the structural links only (grid rows and\n"
    "columns, no shear diagonals; every edge of a mesh cloth), and\n"
    "last_second_median_structural_max_strain the median of that max over the metric samples of\n"
    "the run's last second (a steady reading where the final instant swings; NaN without samples\n"
    "or when the cloth blows up inside that second); median_structural_max_strain_last_1s and\n"
    "median_structural_mean_strain_last_1s the medians of the structural max and mean strain\n"
    "over every step of the last second of simulated time (whatever --sample-every says; NaN\n"
    "when the cloth blows up there). Every strain leaves out links between two kinematic\n"
    "(pinned or grasped) particles. The run stops early at the first sample\n"
    "with a non-finite position or velocity (finite=0, steps = the steps actually run).\n"
    "Exit status 0 "
    "after a run (also with finite=0), 2 for a bad argument, scene key or --load-state file, 1\n"
    "for any other failure.\n"
    "\n"
    "Options:\n"
    "  --config <file>        scene YAML (the format of config/hanging.yaml)\n"
    "  --duration <s>         simulated time, >= 0\n"
    "  --set <key=value>      override a scene key before the run, e.g. solver.substeps=20,\n"
    "                         cloth.pinned=[0,49], grippers.0.radius=0.03; repeatable\n"
    "  --csv <file>           write t,max_strain,mean_strain,energy,max_penetration,\n"
    "                         structural_max_strain,substeps_run,target_met rows (with a header)\n"
    "                         at t = 0 and at every metric sample: every step for scenes of <=\n"
    "                         5000 particles, else every 10th step. substeps_run: the substeps\n"
    "                         the steps since the row before ran (every attempt of a step run\n"
    "                         again counted; 0 for slept steps), target_met: 1 when each of those\n"
    "                         steps met solver.target_max_strain / target_penetration (always 1\n"
    "                         without a target); with every step sampled, the step's own. The\n"
    "                         structural_max_strain of a row is that of its step (with a target,\n"
    "                         what the controller measured)\n"
    "  --sample-every <n>     sample the metrics every n steps instead (n >= 1)\n"
    "  --positions <file>     write the final positions as index,x,y,z lines (no header)\n"
    "  --mesh <file.obj>      write the final cloth as a Wavefront OBJ (v and 1-based f lines)\n"
    "  --save-state <file>    write the final state (binary, saved_state.h): positions,\n"
    "                         velocities, grasps, body poses, contact caches\n"
    "  --load-state <file>    start from a state saved with --save-state on the same scene and\n"
    "                         run --duration more: a run of 2 s equals, bit for bit, a run of 1 s\n"
    "                         saved, loaded and run 1 s more. A file that does not fit the scene\n"
    "                         (particle count, bodies, non-finite values) exits with 2 and the\n"
    "                         reason\n"
    "  --no-simd              the portable loops even where the processor has AVX2 or AVX-512\n"
    "                         (the same results to the bit; for comparing the code paths)\n"
    "  --no-avx512            AVX2 at most, even where the processor has AVX-512 (the same\n"
    "                         results; for comparing the two register widths)\n"
    "  --depth <prefix>       after the run, render every camera of the scene's `cameras:` (each\n"
    "                         needs its pose: no tf here) and write <prefix><name>.pfm, the\n"
    "                         32-bit float depth image (Portable Float Map, rows bottom-up as\n"
    "                         the format says; NaN where nothing is seen); adds depth_ms, the\n"
    "                         mean render time of one image (of 20 renders), to the line\n"
    "  --target-max-strain <e>  instead of one run, search substeps x iterations (iterations\n"
    "                         1, 2, 4, 8; substeps by doubling then bisection up to\n"
    "                         --max-substeps, default 256; settings with at least the passes of\n"
    "                         one that already meets are skipped) for the cheapest measured\n"
    "                         setting whose max_strain over the run is <= e; prints it with its\n"
    "                         cost and a YAML snippet to paste (exit 3 when no setting meets it)\n"
    "  --target-mean-strain <e>  the same for the final mean_strain\n"
    "  --quiet                no progress message on stderr; the result line is still printed\n"
    "  --help                 this text\n";

constexpr int kLargeScene = 5000;  // particles; above it the metrics are sampled every 10th step

using pbd_cloth::bench::UsageError;

struct Options : pbd_cloth::bench::CommonOptions {
  std::string save_state;          // --save-state: the final state goes there
  std::string load_state;          // --load-state: the run starts from it
  std::string depth;               // --depth: prefix of the depth images written after the run
  double target_max_strain = 0.0;  // > 0: search the cheapest setting instead of one run
  double target_mean_strain = 0.0;
  int max_substeps = 256;  // upper end of the search
  // Comparison-only switches (once the scene keys solver.simd and solver.avx512): they set
  // SolverConfig::simd and ::avx512, which change which code runs, never the results.
  bool no_simd = false;
  bool no_avx512 = false;
};

Options parseArguments(int argc, char** argv) {
  namespace bench = pbd_cloth::bench;
  Options options;
  bench::forEachOption(argc, argv, [&](const std::string& option, const bench::NextValue& next) {
    if (option == "--help" || option == "-h") {
      std::cout << kUsage;
      std::exit(0);
    }
    if (bench::parseCommonOption(option, next, options)) return true;
    if (option == "--target-max-strain" || option == "--target-mean-strain") {
      const double target = bench::parseNumber(option, next());
      if (!(target > 0.0 && std::isfinite(target))) {
        throw UsageError(option + ": must be a strain > 0, e.g. 0.01");
      }
      (option == "--target-max-strain" ? options.target_max_strain : options.target_mean_strain) =
          target;
    } else if (option == "--save-state") {
      options.save_state = next();
    } else if (option == "--load-state") {
      options.load_state = next();
    } else if (option == "--depth") {
      options.depth = next();
    } else if (option == "--max-substeps") {
      options.max_substeps = bench::parseCount(option, next(), 1, 100000);
    } else if (option == "--no-simd") {
      options.no_simd = true;
    } else if (option == "--no-avx512") {
      options.no_avx512 = true;
    } else {
      return false;
    }
    return true;
  });
  bench::requireCommonOptions(options);
  if (options.target_max_strain > 0.0 && options.target_mean_strain > 0.0) {
    throw UsageError("give --target-max-strain or --target-mean-strain, not both");
  }
  if ((options.target_max_strain > 0.0 || options.target_mean_strain > 0.0) &&
      (!options.save_state.empty() || !options.load_state.empty())) {
    throw UsageError("--save-state and --load-state are for one run, not the target search");
  }
  return options;
}

void writePositions(std::ofstream& out, const pbd_cloth::Particles& particles) {
  for (int i = 0; i < particles.size(); ++i) {
    const pbd_cloth::Vec3& x = particles.position[i];
    out << i << ',' << x.x() << ',' << x.y() << ',' << x.z() << '\n';
  }
}

void writeMesh(std::ofstream& out, const pbd_cloth::Simulation& sim) {
  const pbd_cloth::Particles& particles = sim.particles();
  const pbd_cloth::ClothTopology& topology = sim.topology();
  out << "# pbd_cloth " << topology.rows << " x " << topology.cols << " cloth at t = " << sim.time()
      << " s\n";
  for (int i = 0; i < particles.cloth_count; ++i) {
    const pbd_cloth::Vec3& x = particles.position[i];
    out << "v " << x.x() << ' ' << x.y() << ' ' << x.z() << '\n';
  }
  const std::vector<unsigned>& t = topology.triangles;
  for (std::size_t k = 0; k + 2 < t.size(); k += 3) {
    out << "f " << t[k] + 1 << ' ' << t[k + 1] + 1 << ' ' << t[k + 2] + 1 << '\n';
  }
}

// What one run measured.
struct BenchResult {
  long long steps = 0;
  double sim_time = 0.0;
  double wall_ms_per_step = 0.0;
  // Processor time of the step calls: on a shared machine it leaves out the time the process
  // waited for a core, which the wall time includes.
  double cpu_ms_per_step = 0.0;
  // Sleeping: steps slept through (a check, not a solve), their mean wall time and the others'.
  long long asleep_steps = 0;
  double asleep_ms_per_step = 0.0;
  double awake_ms_per_step = 0.0;
  double max_strain = 0.0;  // max over the run
  double max_penetration = 0.0;
  int max_self_intersections = 0;
  pbd_cloth::Metrics final_metrics;
  double iterations_per_step = 0.0;
  double predict_ms = 0.0, collide_ms = 0.0, project_ms = 0.0, update_ms = 0.0, contact_ms = 0.0;
  double broad_phase_runs = 0.0;  // per step: 1, plus re-runs for particles that left their boxes
  double local_searches = 0.0;    // per step: searches for a few such particles alone
  // Self-collision candidates per step (the last broad phase of each step), mean over the run.
  double vertex_triangle_pairs = 0.0, edge_edge_pairs = 0.0;
  double search_window = 0.0;  // substeps per contact search, mean over the steps
  // Self-collision searches over the run that stopped at their candidate budget (a cloth crushed
  // into itself; SelfCollision::kPairsPerElement): 0 in every shipped scene.
  long long truncated_searches = 0;
  // Steps solver.adaptive_threads ran on the calling thread alone (thread_choice.h).
  long long solo_steps = 0;
  // Steps of links alone, run with the particles in columns (StepStats::links_in_columns).
  long long columns_steps = 0;
  // Accuracy on demand (Simulation::accuracy()): the fraction of the steps that met the targets,
  // the substeps run per step (every attempt), the steps run again.
  double target_met_fraction = 1.0;
  double mean_substeps = 0.0;
  long long redone_steps = 0;
  // The largest structural max strain over every step (not only the metric samples).
  double worst_structural_max_strain = 0.0;
  // With a target: the steps that missed it at solver.max_substeps, and the largest error over
  // the target of every other step (issue target "no step over it by more than 50 %").
  long long budget_exhausted_steps = 0;
  double worst_target_ratio_within_budget = 0.0;
  // With a target: the controller's measure-and-decide work, timed here (see kUsage).
  double controller_ms_per_step = 0.0;
  int particles = 0;
  int sample_every = 1;
  double depth_ms = -1.0;  // --depth: mean time to render one image; < 0: not asked
  double last_second_median_structural_max_strain = 0.0;  // bench::LastSecondStrain
  // bench::LastSecondStepStrain: every step of the last second of simulated time.
  double median_structural_max_strain_last_1s = 0.0;
  double median_structural_mean_strain_last_1s = 0.0;
};

// Writes depth as a Portable Float Map: "Pf", size, a negative scale for little-endian floats,
// then rows from the bottom up.
void writePfm(const std::string& path, const pbd_cloth::PinholeCamera& camera,
              const std::vector<float>& depth) {
  std::ofstream out(path, std::ios::binary);
  out << "Pf\n" << camera.width << ' ' << camera.height << "\n-1.0\n";
  for (int v = camera.height - 1; v >= 0; --v) {
    out.write(
        reinterpret_cast<const char*>(depth.data() + static_cast<std::size_t>(v) * camera.width),
        static_cast<std::streamsize>(camera.width * sizeof(float)));
  }
  if (!out) throw std::runtime_error("--depth: cannot write '" + path + "'");
}

// --depth: every camera's image of the final state; returns the mean render time (ms) of one
// image over 20 renders of each camera.
double writeDepthImages(const pbd_cloth::SceneConfig& scene, const pbd_cloth::Simulation& sim,
                        const std::string& prefix) {
  using Clock = std::chrono::steady_clock;
  if (scene.cameras.empty()) throw UsageError("--depth: the scene has no cameras");
  pbd_cloth::DepthSnapshot snapshot;
  snapshot.capture(sim);
  pbd_cloth::DepthRenderer renderer;
  double seconds = 0.0;
  int renders = 0;
  for (std::size_t k = 0; k < scene.cameras.size(); ++k) {
    const pbd_cloth::CameraConfig& config = scene.cameras[k];
    if (!config.has_pose) {
      throw UsageError("--depth: cameras[" + std::to_string(k) + "].pose is needed ('" +
                       config.name + "' follows tf in the node; cloth_bench has no tf)");
    }
    const pbd_cloth::PinholeCamera camera = pbd_cloth::PinholeCamera::fromConfig(config);
    const pbd_cloth::Frame pose = pbd_cloth::frameFromPose(config.pose);
    std::vector<float> depth(camera.pixelCount());
    for (int r = 0; r < 20; ++r) {
      const Clock::time_point begin = Clock::now();
      renderer.render(snapshot, camera, pose, depth.data());
      seconds += std::chrono::duration<double>(Clock::now() - begin).count();
      ++renders;
    }
    // The node's noise for the image at this time.
    pbd_cloth::addCameraNoise(depth.data(), depth.size(), config, k, sim.time());
    writePfm(prefix + config.name + ".pfm", camera, depth);
  }
  return 1e3 * seconds / renders;
}

// Runs the scene for `duration` seconds of 1/step_rate steps. Only the step calls are timed.
// Writes the CSV samples as it goes and the final positions / mesh to the streams that are open.
BenchResult simulate(const pbd_cloth::SceneConfig& scene, const Options& options,
                     std::ofstream& csv, std::ofstream& positions, std::ofstream& mesh) {
  pbd_cloth::Simulation sim(scene);
  for (const std::string& warning : sim.startWarnings()) {
    std::fprintf(stderr, "warning: %s\n", warning.c_str());
  }
  if (!options.load_state.empty()) {
    pbd_cloth::SimulationState state;
    std::string reason;
    if (!pbd_cloth::readStateFile(options.load_state, state, reason) ||
        !sim.setState(state, reason)) {
      throw pbd_cloth::ConfigError("--load-state", "'" + options.load_state + "': " + reason);
    }
  }
  const double step_count = options.duration * scene.step_rate;
  if (step_count > std::numeric_limits<int>::max()) {
    throw UsageError("--duration: " + std::to_string(step_count) + " steps are too many");
  }
  const long long steps = std::llround(step_count);
  BenchResult result;
  result.particles = sim.particles().size();
  result.sample_every =
      options.sample_every > 0 ? options.sample_every : (result.particles <= kLargeScene ? 1 : 10);
  if (!options.quiet) {
    std::cerr << "cloth_bench: " << options.config << ": " << result.particles << " particles, "
              << sim.topology().triangleCount() << " triangles, " << steps << " steps of "
              << 1.0 / scene.step_rate << " s, metrics every " << result.sample_every
              << " step(s)\n";
  }

  pbd_cloth::bench::LastSecondStrain last_second(steps, scene.step_rate, result.sample_every);
  pbd_cloth::bench::LastSecondStepStrain last_second_steps(steps, scene.step_rate);
  pbd_cloth::Metrics last = sim.computeMetrics();
  result.max_strain = last.max_strain;
  result.max_penetration = last.max_penetration;
  result.max_self_intersections = last.self_intersections;
  pbd_cloth::bench::writeCsvRow(csv, sim.time(), last, ",0,1");

  double step_seconds = 0.0;
  std::clock_t step_cpu = 0;
  double predict = 0.0, collide = 0.0, project = 0.0, update = 0.0, contact = 0.0;
  long long broad_phase_runs = 0, local_searches = 0;
  long long vertex_triangle_pairs = 0, edge_edge_pairs = 0;
  long long search_window = 0;
  long long truncated_searches = 0;
  long long solo_steps = 0;
  long long columns_steps = 0;
  long long met_steps = 0, substeps_run = 0, redone_steps = 0;
  // Since the last CSV row: substeps run, and whether every step met the target.
  long long row_substeps = 0;
  bool row_met = true;
  double worst_structural = 0.0;
  long long budget_exhausted_steps = 0;
  double worst_ratio_within_budget = 0.0;
  // The controller's own work, timed on a copy of the work it does (Simulation::solveStep): the
  // structural strain once an attempt, the particles copied once an attempt (the step's start,
  // then each redo's restore). A scratch copy, sized once, as the core's.
  pbd_cloth::Particles controller_scratch = sim.particles();
  double controller_seconds = 0.0;
  long long iterations = 0;
  long long done = 0;
  double asleep_seconds = 0.0, awake_seconds = 0.0;
  long long asleep_steps = 0;
  using Clock = std::chrono::steady_clock;
  while (done < steps) {
    const long slept_before = sim.sleeping().sleptSteps();
    const Clock::time_point begin = Clock::now();
    const std::clock_t cpu_begin = std::clock();
    sim.step();
    step_cpu += std::clock() - cpu_begin;
    const double seconds = std::chrono::duration<double>(Clock::now() - begin).count();
    step_seconds += seconds;
    // Sleeping (solver.sleep_speed): the steps it slept through and the others, timed apart.
    if (sim.sleeping().sleptSteps() > slept_before) {
      asleep_seconds += seconds;
      ++asleep_steps;
    } else {
      awake_seconds += seconds;
      if (sim.solver().stats().on_one_thread) ++solo_steps;
      if (sim.solver().stats().links_in_columns) ++columns_steps;
    }
    const pbd_cloth::Simulation::AccuracyReport& accuracy = sim.accuracy();
    if (accuracy.target_met) ++met_steps;
    substeps_run += accuracy.substeps_run;
    if (accuracy.redos > 0) ++redone_steps;
    if (accuracy.budget_exhausted) {
      ++budget_exhausted_steps;
    } else if (accuracy.active && accuracy.substeps_run > 0) {
      const double ratio =
          sim.accuracyController().ratio(accuracy.structural_max_strain, accuracy.max_penetration);
      if (!(ratio <= worst_ratio_within_budget)) worst_ratio_within_budget = ratio;
    }
    row_substeps += accuracy.substeps_run;
    row_met = row_met && accuracy.target_met;
    // The step's structural max strain: what the controller measured, or measured here without
    // a target (outside the timed step call).
    double step_structural = accuracy.structural_max_strain;
    if (accuracy.active && accuracy.substeps_run > 0) {  // a slept step measures nothing
      const Clock::time_point measure_begin = Clock::now();
      double structural_max = 0.0, structural_mean = 0.0;
      pbd_cloth::computeStructuralStrain(sim.particles(), sim.topology(), structural_max,
                                         structural_mean);
      controller_scratch = sim.particles();
      controller_seconds += (1 + accuracy.redos) *
                            std::chrono::duration<double>(Clock::now() - measure_begin).count();
    } else if (!accuracy.active) {
      double structural_mean = 0.0;
      pbd_cloth::computeStructuralStrain(sim.particles(), sim.topology(), step_structural,
                                         structural_mean);
    }
    // A NaN (a blown-up cloth) is the worst there is.
    if (!(step_structural <= worst_structural)) worst_structural = step_structural;
    ++done;
    // The solver's figures (sim.stats() would also measure the state, as a report does).
    const pbd_cloth::StepStats& stats = sim.solver().stats();
    predict += stats.predict_time;
    collide += stats.collide_time;
    project += stats.project_time;
    update += stats.update_time;
    contact += stats.contact_time;
    broad_phase_runs += sim.collisions().stats().broad_phase_runs;
    local_searches += sim.collisions().stats().local_searches;
    vertex_triangle_pairs += sim.collisions().stats().vertex_triangle_pairs;
    edge_edge_pairs += sim.collisions().stats().edge_edge_pairs;
    search_window += sim.collisions().stats().search_window;
    truncated_searches += sim.collisions().stats().truncated_searches;
    iterations += stats.iterations;
    if (last_second_steps.counts(done)) {
      double structural_max = 0.0, structural_mean = 0.0;
      pbd_cloth::computeStructuralStrain(sim.particles(), sim.topology(), structural_max,
                                         structural_mean);
      last_second_steps.add(structural_max, structural_mean);
    }
    if (done % result.sample_every != 0 && done != steps) continue;
    last = sim.computeMetrics();
    result.max_strain = std::max(result.max_strain, last.max_strain);
    result.max_penetration = std::max(result.max_penetration, last.max_penetration);
    result.max_self_intersections =
        std::max(result.max_self_intersections, last.self_intersections);
    pbd_cloth::bench::writeCsvRow(csv, sim.time(), last,
                                  "," + std::to_string(row_substeps) + (row_met ? ",1" : ",0"));
    row_substeps = 0;
    row_met = true;
    last_second.add(done, last);
    // A diverged state stays diverged; stepping NaNs further only costs time.
    if (!last.finite) break;
  }
  if (positions.is_open()) writePositions(positions, sim.particles());
  if (mesh.is_open()) writeMesh(mesh, sim);
  if (!options.depth.empty()) result.depth_ms = writeDepthImages(scene, sim, options.depth);
  if (!options.save_state.empty()) {
    pbd_cloth::SimulationState state;
    sim.getState(state);
    std::string reason;
    if (!pbd_cloth::writeStateFile(options.save_state, state, reason)) {
      throw std::runtime_error("--save-state: " + reason);
    }
  }
  const double per_step = done > 0 ? 1.0 / static_cast<double>(done) : 0.0;
  result.steps = done;
  result.sim_time = sim.time();
  result.final_metrics = last;
  result.last_second_median_structural_max_strain = last_second.median();
  result.median_structural_max_strain_last_1s = last_second_steps.medianMax();
  result.median_structural_mean_strain_last_1s = last_second_steps.medianMean();
  result.wall_ms_per_step = 1e3 * step_seconds * per_step;
  result.cpu_ms_per_step = 1e3 * static_cast<double>(step_cpu) / CLOCKS_PER_SEC * per_step;
  result.asleep_steps = asleep_steps;
  result.asleep_ms_per_step = asleep_steps > 0 ? 1e3 * asleep_seconds / asleep_steps : 0.0;
  result.awake_ms_per_step =
      done > asleep_steps ? 1e3 * awake_seconds / (done - asleep_steps) : 0.0;
  result.iterations_per_step = static_cast<double>(iterations) * per_step;
  result.predict_ms = 1e3 * predict * per_step;
  result.collide_ms = 1e3 * collide * per_step;
  result.project_ms = 1e3 * project * per_step;
  result.update_ms = 1e3 * update * per_step;
  result.contact_ms = 1e3 * contact * per_step;
  result.broad_phase_runs = static_cast<double>(broad_phase_runs) * per_step;
  result.local_searches = static_cast<double>(local_searches) * per_step;
  result.vertex_triangle_pairs = static_cast<double>(vertex_triangle_pairs) * per_step;
  result.edge_edge_pairs = static_cast<double>(edge_edge_pairs) * per_step;
  result.search_window = static_cast<double>(search_window) * per_step;
  result.truncated_searches = truncated_searches;
  result.solo_steps = solo_steps;
  result.columns_steps = columns_steps;
  result.target_met_fraction = static_cast<double>(met_steps) * per_step;
  result.mean_substeps = static_cast<double>(substeps_run) * per_step;
  result.redone_steps = redone_steps;
  result.worst_structural_max_strain = worst_structural;
  result.budget_exhausted_steps = budget_exhausted_steps;
  result.worst_target_ratio_within_budget = worst_ratio_within_budget;
  result.controller_ms_per_step = 1e3 * controller_seconds * per_step;
  return result;
}

void printResult(const pbd_cloth::SceneConfig& scene, const BenchResult& r) {
  const pbd_cloth::Metrics& last = r.final_metrics;
  std::printf(
      "wall_ms_per_step=%.6g max_strain=%.9g mean_strain=%.9g max_penetration=%.9g "
      "self_intersections=%d energy=%.9g finite=%d steps=%lld sim_time=%.9g "
      "iterations_per_step=%.6g predict_ms=%.6g collide_ms=%.6g project_ms=%.6g update_ms=%.6g "
      "method=%s substeps=%d iterations=%d particles=%d max_self_intersections=%d "
      "sample_every=%d final_max_strain=%.9g ordering=%s contact_ms=%.6g broad_phase_runs=%.6g "
      "final_structural_max_strain=%.9g final_structural_mean_strain=%.9g cpu_ms_per_step=%.6g "
      "asleep_steps=%lld asleep_ms_per_step=%.6g awake_ms_per_step=%.6g "
      "vertex_triangle_pairs=%.6g edge_edge_pairs=%.6g search_window=%.6g "
      "truncated_searches=%lld local_searches=%.6g last_second_median_structural_max_strain=%.9g "
      "solo_steps=%lld threads=%d columns_steps=%lld median_structural_max_strain_last_1s=%.9g "
      "median_structural_mean_strain_last_1s=%.9g target_met_fraction=%.6g mean_substeps=%.6g "
      "redone_steps=%lld worst_structural_max_strain=%.9g controller_ms_per_step=%.6g "
      "controller_fraction=%.6g budget_exhausted_steps=%lld "
      "worst_target_ratio_within_budget=%.6g",
      r.wall_ms_per_step, r.max_strain, last.mean_strain, r.max_penetration,
      last.self_intersections, last.energy, last.finite ? 1 : 0, r.steps, r.sim_time,
      r.iterations_per_step, r.predict_ms, r.collide_ms, r.project_ms, r.update_ms,
      pbd_cloth::toString(scene.solver.method), scene.solver.substeps, scene.solver.iterations,
      r.particles, r.max_self_intersections, r.sample_every, last.max_strain,
      pbd_cloth::toString(scene.solver.ordering), r.contact_ms, r.broad_phase_runs,
      last.structural_max_strain, last.structural_mean_strain, r.cpu_ms_per_step, r.asleep_steps,
      r.asleep_ms_per_step, r.awake_ms_per_step, r.vertex_triangle_pairs, r.edge_edge_pairs,
      r.search_window, r.truncated_searches, r.local_searches,
      r.last_second_median_structural_max_strain, r.solo_steps, scene.solver.threads,
      r.columns_steps, r.median_structural_max_strain_last_1s,
      r.median_structural_mean_strain_last_1s, r.target_met_fraction, r.mean_substeps,
      r.redone_steps, r.worst_structural_max_strain, r.controller_ms_per_step,
      r.wall_ms_per_step > 0.0 ? r.controller_ms_per_step / r.wall_ms_per_step : 0.0,
      r.budget_exhausted_steps, r.worst_target_ratio_within_budget);
  if (r.depth_ms >= 0.0) std::printf(" depth_ms=%.6g", r.depth_ms);
  std::printf("\n");
}

// --target-max-strain / --target-mean-strain: the cheapest substeps x iterations that meet the
// target on this scene. For each iteration count the smallest substep count that meets it is
// found by bisection (error falls as substeps rise: Small Steps, sec. 4), every candidate's cost is
// measured, and the cheapest measured wall time wins.
int searchCheapest(const pbd_cloth::SceneConfig& base, const Options& options) {
  const bool use_max = options.target_max_strain > 0.0;
  const double target = use_max ? options.target_max_strain : options.target_mean_strain;
  const char* metric = use_max ? "max_strain" : "mean_strain";
  Options quiet = options;
  quiet.quiet = true;
  std::ofstream no_output;
  auto measure = [&](int substeps, int iterations, BenchResult& out) {
    pbd_cloth::SceneConfig scene = base;
    scene.solver.substeps = substeps;
    scene.solver.iterations = iterations;
    out = simulate(scene, quiet, no_output, no_output, no_output);
    const double error = use_max ? out.max_strain : out.final_metrics.mean_strain;
    const bool meets = out.final_metrics.finite && error <= target;
    std::fprintf(
        stderr, "cloth_bench: substeps=%d iterations=%d %s=%.4g wall_ms_per_step=%.4g %s\n",
        substeps, iterations, metric, error, out.wall_ms_per_step, meets ? "meets" : "misses");
    return meets;
  };
  struct Candidate {
    int substeps = 0, iterations = 0;
    BenchResult result;
  };
  std::vector<Candidate> found;
  // A step costs about its number of passes (substeps x iterations; the broad phase and the
  // velocity update are a small part), so once a setting meets the target no setting with as many
  // passes or more is measured: it cannot be cheaper. This keeps the search to a few runs.
  int fewest_passes = std::numeric_limits<int>::max();
  for (int iterations : {1, 2, 4, 8}) {
    int low = 0, high = 1;  // low misses (0 = none tried), high is the candidate that meets
    BenchResult result;
    bool met = false;
    while (high <= options.max_substeps && high * iterations < fewest_passes) {
      if (measure(high, iterations, result)) {
        met = true;
        break;
      }
      low = high;
      high *= 2;
    }
    if (!met) continue;
    BenchResult best = result;
    while (high - low > 1) {
      const int mid = (low + high) / 2;
      if (measure(mid, iterations, result)) {
        high = mid;
        best = result;
      } else {
        low = mid;
      }
    }
    found.push_back({high, iterations, best});
    fewest_passes = std::min(fewest_passes, high * iterations);
  }
  if (found.empty()) {
    std::printf("target_%s=%.6g met=0 max_substeps=%d\n", metric, target, options.max_substeps);
    return 3;
  }
  const Candidate& cheapest =
      *std::min_element(found.begin(), found.end(), [](const Candidate& a, const Candidate& b) {
        return a.result.wall_ms_per_step < b.result.wall_ms_per_step;
      });
  const double error =
      use_max ? cheapest.result.max_strain : cheapest.result.final_metrics.mean_strain;
  std::printf(
      "target_%s=%.6g met=1 substeps=%d iterations=%d %s=%.6g wall_ms_per_step=%.6g "
      "method=%s ordering=%s\n",
      metric, target, cheapest.substeps, cheapest.iterations, metric, error,
      cheapest.result.wall_ms_per_step, pbd_cloth::toString(base.solver.method),
      pbd_cloth::toString(base.solver.ordering));
  std::printf("# paste into the scene YAML:\nsolver:\n  substeps: %d\n  iterations: %d\n",
              cheapest.substeps, cheapest.iterations);
  return 0;
}

int run(const Options& options) {
  pbd_cloth::SceneConfig scene = pbd_cloth::bench::loadScene(options);
  if (options.no_simd) scene.solver.simd = false;
  if (options.no_avx512) scene.solver.avx512 = false;
  if (options.target_max_strain > 0.0 || options.target_mean_strain > 0.0) {
    return searchCheapest(scene, options);
  }

  std::ofstream csv = pbd_cloth::bench::openOutput("--csv", options.csv);
  std::ofstream positions = pbd_cloth::bench::openOutput("--positions", options.positions);
  std::ofstream mesh = pbd_cloth::bench::openOutput("--mesh", options.mesh);
  // Written after the run; opened now only so a bad path fails before it.
  std::ofstream state_file = pbd_cloth::bench::openOutput("--save-state", options.save_state);
  state_file.close();
  pbd_cloth::bench::writeCsvHeader(csv, ",substeps_run,target_met");

  const BenchResult result = simulate(scene, options, csv, positions, mesh);
  pbd_cloth::bench::finishOutput(csv, options.csv);
  pbd_cloth::bench::finishOutput(positions, options.positions);
  pbd_cloth::bench::finishOutput(mesh, options.mesh);
  printResult(scene, result);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return pbd_cloth::bench::runTool("cloth_bench", [&] { return run(parseArguments(argc, argv)); });
}
