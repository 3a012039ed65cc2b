// cloth_bench as a user runs it (the program, its output line, its files and its exit status),
// the package's source style and its generated meshes. The accuracy tests drive the core directly;
// these check the tool the charts and the README's and doc/benchmarks.md's figures come from.
#include <gtest/gtest.h>
#include <stdlib.h>
#include <sys/wait.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

namespace {

struct BenchRun {
  int status = -1;
  std::string out;  // stdout and stderr
};

// Runs `command` in a shell; its stdout and stderr, and its exit status.
BenchRun runShell(const std::string& command) {
  BenchRun run;
  FILE* pipe = popen((command + " 2>&1").c_str(), "r");
  if (pipe == nullptr) return run;
  std::array<char, 4096> buffer;
  std::size_t n;
  while ((n = std::fread(buffer.data(), 1, buffer.size(), pipe)) > 0)
    run.out.append(buffer.data(), n);
  const int raw = pclose(pipe);
  run.status = WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
  return run;
}

BenchRun runBench(const std::string& arguments) {
  return runShell(std::string(CLOTH_BENCH) + " --config " + PBD_CLOTH_SOURCE_DIR +
                  "/config/hanging.yaml " + arguments);
}

// key=value pairs of the lines of `text` (later lines win).
std::map<std::string, std::string> keyValues(const std::string& text) {
  std::map<std::string, std::string> values;
  std::istringstream words(text);
  std::string word;
  while (words >> word) {
    const std::size_t equals = word.find('=');
    if (equals != std::string::npos && equals > 0) {
      values[word.substr(0, equals)] = word.substr(equals + 1);
    }
  }
  return values;
}

// A 10 x 10 version of the default scene: the same file, scaled down with --set.
const std::string kSmall =
    " --quiet --set cloth.rows=10 --set cloth.cols=10 --set 'cloth.pinned=[0,9]'"
    " --set cloth.spacing=0.1";
// The same without its tethers, whose strain falls with the substeps (with them, one substep
// already meets the target searches' targets).
const std::string kSmallUntethered = kSmall + " --set cloth.tethers=false";

std::string readFile(const std::string& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

TEST(ClothBench, PrintsEveryMetricOfTheInterface) {
  const BenchRun run = runBench("--duration 0.5" + kSmall);
  ASSERT_EQ(run.status, 0) << run.out;
  const auto values = keyValues(run.out);
  for (const char* key :
       {"wall_ms_per_step", "max_strain", "mean_strain", "max_penetration", "self_intersections",
        "energy", "finite", "predict_ms", "collide_ms", "project_ms", "contact_ms", "update_ms"}) {
    EXPECT_EQ(values.count(key), 1u) << "missing " << key << " in: " << run.out;
  }
  EXPECT_EQ(values.at("finite"), "1");
  EXPECT_EQ(values.at("steps"), "30");  // 0.5 s at the scene's 60 Hz
  EXPECT_EQ(values.at("particles"), "100");
}

// columns_steps counts the steps of links alone (Solver::linksAlone): every step of the small
// cloth without bending and tethers, none with its bending on.
TEST(ClothBench, CountsTheStepsOfLinksAlone) {
  const auto alone =
      keyValues(runBench("--duration 0.5 --set cloth.bend_compliance=-1" + kSmallUntethered).out);
  ASSERT_EQ(alone.count("columns_steps"), 1u);
  EXPECT_EQ(alone.at("columns_steps"), "30");
  const auto bending = keyValues(runBench("--duration 0.5" + kSmallUntethered).out);
  ASSERT_EQ(bending.count("columns_steps"), 1u);
  EXPECT_EQ(bending.at("columns_steps"), "0");
}

// solver.taut_chains left the product on 2026-12-07: its metric left the line, and a scene or
// an override that still names the key fails with exit status 2 and a message naming it.
TEST(ClothBench, TautChainsAreGone) {
  const auto line = keyValues(runBench("--duration 0.1" + kSmallUntethered).out);
  EXPECT_EQ(line.count("held_particles"), 0u);
  const BenchRun removed = runBench("--duration 0.1 --set solver.taut_chains=false" + kSmall);
  EXPECT_EQ(removed.status, 2) << removed.out;
  EXPECT_NE(removed.out.find("solver.taut_chains: was removed"), std::string::npos) << removed.out;
}

TEST(ClothBench, WritesPositionsAndMeshOfTheFinalState) {
  const std::string positions = ::testing::TempDir() + "bench_positions.csv";
  const std::string mesh = ::testing::TempDir() + "bench_mesh.obj";
  const BenchRun run =
      runBench("--duration 0.2 --positions " + positions + " --mesh " + mesh + kSmall);
  ASSERT_EQ(run.status, 0) << run.out;
  std::istringstream lines(readFile(positions));
  std::string line;
  int count = 0;
  while (std::getline(lines, line)) {
    int index;
    double x, y, z;
    char c1, c2, c3;
    std::istringstream fields(line);
    ASSERT_TRUE(fields >> index >> c1 >> x >> c2 >> y >> c3 >> z) << line;
    EXPECT_EQ(index, count);
    ++count;
  }
  EXPECT_EQ(count, 100);
  std::istringstream obj(readFile(mesh));
  int vertices = 0, faces = 0;
  while (std::getline(obj, line)) {
    if (line.rfind("v ", 0) == 0) ++vertices;
    if (line.rfind("f ", 0) == 0) ++faces;
  }
  EXPECT_EQ(vertices, 100);
  EXPECT_EQ(faces, 2 * 9 * 9);
}

const char kCsvHeader[] =
    "t,max_strain,mean_strain,energy,max_penetration,structural_max_strain,substeps_run,"
    "target_met";

// Column `column` (0-based) of every row of a --csv file after its header (row 0: t = 0).
std::vector<double> csvColumn(const std::string& csv_path, int column) {
  std::ifstream in(csv_path);
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, kCsvHeader);
  std::vector<double> values;
  while (std::getline(in, line)) {
    std::istringstream fields(line);
    std::string field;
    for (int k = 0; k <= column; ++k) std::getline(fields, field, ',');
    values.push_back(std::stod(field));
  }
  return values;
}

// The structural_max_strain column of --csv, one value a sample row (row 0: t = 0).
std::vector<double> structuralMaxStrains(const std::string& csv_path) {
  return csvColumn(csv_path, 5);
}

// --csv's substeps_run and target_met columns and the line's worst_structural_max_strain, with
// and without a target (issue 51's charts: error and substeps over time). Every step sampled: a
// row per step, so substeps_run sums to the run's, target_met counts its met steps, and the
// worst over the rows is the line's worst. Sampled every 4th step, the rows hold the sums of the
// steps between them and the worst still reads every step.
TEST(ClothBench, CsvHoldsEachStepsSubstepsAndWhetherItMetTheTarget) {
  const std::string csv = ::testing::TempDir() + "bench_accuracy.csv";
  const std::string target =
      " --set solver.target_max_strain=0.002 --set solver.min_substeps=2"
      " --set solver.max_substeps=64 --set solver.substeps=2";
  for (const std::string& setting : {std::string(" --set solver.substeps=3"), target}) {
    const BenchRun run =
        runBench("--duration 1 --sample-every 1 --csv " + csv + kSmallUntethered + setting);
    ASSERT_EQ(run.status, 0) << run.out;
    const auto values = keyValues(run.out);
    const std::vector<double> strain = structuralMaxStrains(csv);
    const std::vector<double> substeps = csvColumn(csv, 6);
    const std::vector<double> met = csvColumn(csv, 7);
    ASSERT_EQ(strain.size(), 61u);
    EXPECT_EQ(substeps[0], 0.0);
    EXPECT_EQ(met[0], 1.0);
    double total = 0.0, met_steps = 0.0;
    for (std::size_t k = 1; k < substeps.size(); ++k) {
      total += substeps[k];
      met_steps += met[k];
    }
    EXPECT_NEAR(total / 60.0, std::stod(values.at("mean_substeps")), 1e-4) << setting;
    EXPECT_NEAR(met_steps / 60.0, std::stod(values.at("target_met_fraction")), 1e-4) << setting;
    const double worst = std::stod(values.at("worst_structural_max_strain"));
    EXPECT_NEAR(*std::max_element(strain.begin(), strain.end()), worst, 1e-9 + 1e-6 * worst);
    ASSERT_EQ(values.count("controller_fraction"), 1u);
    if (setting == target) {
      EXPECT_GT(std::stod(values.at("controller_ms_per_step")), 0.0);
      EXPECT_GT(*std::max_element(substeps.begin(), substeps.end()), 2.0) << "never raised";
      for (std::size_t k = 1; k < met.size(); ++k) {
        EXPECT_EQ(met[k] == 1.0, strain[k] <= 0.002) << "row " << k;
      }
    } else {
      EXPECT_EQ(values.at("controller_ms_per_step"), "0");
      EXPECT_EQ(met_steps, 60.0);
      for (std::size_t k = 1; k < substeps.size(); ++k) EXPECT_EQ(substeps[k], 3.0);
    }
    // Every 4th step: the rows sum the steps since the row before; the worst is the same.
    const BenchRun sparse =
        runBench("--duration 1 --sample-every 4 --csv " + csv + kSmallUntethered + setting);
    ASSERT_EQ(sparse.status, 0) << sparse.out;
    const std::vector<double> sums = csvColumn(csv, 6);
    EXPECT_EQ(sums.size(), 16u);  // t = 0 and 15 samples
    double sparse_total = 0.0;
    for (double value : sums) sparse_total += value;
    EXPECT_EQ(sparse_total, total) << setting;
    EXPECT_EQ(keyValues(sparse.out).at("worst_structural_max_strain"),
              values.at("worst_structural_max_strain"));
  }
}

double medianOf(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  const std::size_t n = values.size();
  return n % 2 == 1 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

// last_second_median_structural_max_strain is the median of the samples of the run's last second:
// here every step is sampled, so the last 60 of a 2 s run at 60 Hz, and the sample that ends the
// second before them (rows 60 to 120 of the CSV). A 20 x 20 swinging cloth at few substeps still
// whips at 2 s, so the whole run's median and the last second's differ, and a wrong window
// shows. The CSV holds six digits: the tolerance.
TEST(ClothBench, LastSecondMedianIsTheMedianOfTheLastSecondsSamples) {
  const std::string csv = ::testing::TempDir() + "bench_last_second.csv";
  const std::string swinging = std::string(" --config ") + PBD_CLOTH_SOURCE_DIR +
                               "/config/swinging.yaml --quiet --set cloth.rows=20"
                               " --set cloth.cols=20 --set 'cloth.pinned=[0,19]'"
                               " --set cloth.spacing=0.05 --set solver.substeps=4"
                               " --sample-every 1 --csv " +
                               csv;
  BenchRun run = runShell(std::string(CLOTH_BENCH) + swinging + " --duration 2");
  ASSERT_EQ(run.status, 0) << run.out;
  const double printed =
      std::stod(keyValues(run.out).at("last_second_median_structural_max_strain"));
  std::vector<double> samples = structuralMaxStrains(csv);
  ASSERT_EQ(samples.size(), 121u);  // t = 0 and 120 steps
  const double last_second = medianOf(std::vector<double>(samples.begin() + 60, samples.end()));
  const double whole_run = medianOf(std::vector<double>(samples.begin() + 1, samples.end()));
  EXPECT_NEAR(printed, last_second, 1e-5 * last_second);
  EXPECT_GT(std::abs(whole_run - last_second), 1e-3 * last_second) << "the test cannot tell";
  // The final instant's value is the CSV's last row.
  EXPECT_NEAR(std::stod(keyValues(run.out).at("final_structural_max_strain")), samples.back(),
              1e-5 * samples.back());

  // A run shorter than a second: every sample after the start (rows 1 to 30).
  run = runShell(std::string(CLOTH_BENCH) + swinging + " --duration 0.5");
  ASSERT_EQ(run.status, 0) << run.out;
  samples = structuralMaxStrains(csv);
  ASSERT_EQ(samples.size(), 31u);
  EXPECT_NEAR(std::stod(keyValues(run.out).at("last_second_median_structural_max_strain")),
              medianOf(std::vector<double>(samples.begin() + 1, samples.end())),
              1e-5 * samples.back() + 1e-12);
}

// median_structural_max_strain_last_1s and ..._mean_...: the medians over every step of the last
// second of simulated time, whatever --sample-every says (the CSV's rows at --sample-every 1 are
// those steps), and the mean below the max.
TEST(ClothBench, MedianOfTheLastSecondReadsEveryStep) {
  const std::string csv = ::testing::TempDir() + "bench_last_1s.csv";
  const std::string swinging = std::string(" --config ") + PBD_CLOTH_SOURCE_DIR +
                               "/config/swinging.yaml --quiet --set cloth.rows=20"
                               " --set cloth.cols=20 --set 'cloth.pinned=[0,19]'"
                               " --set cloth.spacing=0.05 --set solver.substeps=4 --duration 2";
  const BenchRun every =
      runShell(std::string(CLOTH_BENCH) + swinging + " --sample-every 1 --csv " + csv);
  ASSERT_EQ(every.status, 0) << every.out;
  const auto values = keyValues(every.out);
  ASSERT_EQ(values.count("median_structural_max_strain_last_1s"), 1u) << every.out;
  ASSERT_EQ(values.count("median_structural_mean_strain_last_1s"), 1u) << every.out;
  const double median_max = std::stod(values.at("median_structural_max_strain_last_1s"));
  const double median_mean = std::stod(values.at("median_structural_mean_strain_last_1s"));
  std::vector<double> samples = structuralMaxStrains(csv);
  ASSERT_EQ(samples.size(), 121u);  // t = 0 and 120 steps: the last second is steps 60 to 120
  EXPECT_NEAR(median_max, medianOf(std::vector<double>(samples.begin() + 60, samples.end())),
              1e-5 * median_max);
  EXPECT_GT(median_mean, 0.0);
  EXPECT_LT(median_mean, median_max);
  // Sampled every 7th step, the medians over the steps are the same, to the printed digit.
  const auto sparse =
      keyValues(runShell(std::string(CLOTH_BENCH) + swinging + " --sample-every 7").out);
  EXPECT_EQ(sparse.at("median_structural_max_strain_last_1s"),
            values.at("median_structural_max_strain_last_1s"));
  EXPECT_EQ(sparse.at("median_structural_mean_strain_last_1s"),
            values.at("median_structural_mean_strain_last_1s"));
}

// A cloth that blows up inside the window has no steady strain: NaN, though its last sample's
// strain reads 0 (NaN positions compare false). An explicit mass-spring cloth, one substep of a
// 60 Hz step at a stiffness far past its limit, is not finite after about 36 steps.
TEST(ClothBench, LastSecondMedianOfABlownUpClothIsNaN) {
  const BenchRun run = runBench("--duration 0.9 --sample-every 1" + kSmall +
                                " --set solver.method=mass_spring --set solver.substeps=1"
                                " --set solver.spring_stiffness=100000");
  ASSERT_EQ(run.status, 0) << run.out;
  const auto values = keyValues(run.out);
  ASSERT_EQ(values.at("finite"), "0") << "the run must blow up for this test: " << run.out;
  EXPECT_LT(std::stoi(values.at("steps")), 54) << "inside the run's 54 steps";
  EXPECT_EQ(values.at("last_second_median_structural_max_strain"), "nan") << run.out;
}

TEST(ClothBench, RunsAreBitIdentical) {
  const std::string a = ::testing::TempDir() + "bench_a.csv";
  const std::string b = ::testing::TempDir() + "bench_b.csv";
  ASSERT_EQ(runBench("--duration 0.5 --positions " + a + kSmall).status, 0);
  ASSERT_EQ(runBench("--duration 0.5 --positions " + b + kSmall).status, 0);
  const std::string first = readFile(a);
  EXPECT_FALSE(first.empty());
  EXPECT_EQ(first, readFile(b));
}

// The comparison switches (once solver.simd and solver.avx512) change which code runs, never the
// positions; the old keys name the flags that replaced them.
TEST(ClothBench, NoSimdAndNoAvx512GiveTheSamePositions) {
  const std::string a = ::testing::TempDir() + "bench_simd.csv";
  const std::string b = ::testing::TempDir() + "bench_no_simd.csv";
  const std::string c = ::testing::TempDir() + "bench_no_avx512.csv";
  ASSERT_EQ(runBench("--duration 0.5 --positions " + a + kSmall).status, 0);
  ASSERT_EQ(runBench("--duration 0.5 --no-simd --positions " + b + kSmall).status, 0);
  ASSERT_EQ(runBench("--duration 0.5 --no-avx512 --positions " + c + kSmall).status, 0);
  const std::string first = readFile(a);
  EXPECT_FALSE(first.empty());
  EXPECT_EQ(first, readFile(b));
  EXPECT_EQ(first, readFile(c));
  const BenchRun help = runShell(std::string(CLOTH_BENCH) + " --help");
  EXPECT_NE(help.out.find("--no-simd"), std::string::npos);
  EXPECT_NE(help.out.find("--no-avx512"), std::string::npos);
  const BenchRun old_key = runBench("--duration 0.1 --set solver.simd=false");
  EXPECT_EQ(old_key.status, 2);
  EXPECT_NE(old_key.out.find("solver.simd: moved to cloth_bench --no-simd"), std::string::npos)
      << old_key.out;
}

TEST(ClothBench, BadKeyOrArgumentExitsWithTwoAndNamesIt) {
  BenchRun run = runBench("--duration 0.1 --set solver.substepz=3");
  EXPECT_EQ(run.status, 2);
  EXPECT_NE(run.out.find("substepz"), std::string::npos) << run.out;
  run = runBench("--duration 0.1 --set solver.substeps=0");
  EXPECT_EQ(run.status, 2);
  EXPECT_NE(run.out.find("solver.substeps"), std::string::npos) << run.out;
  run = runBench("--duration soon");
  EXPECT_EQ(run.status, 2);
  EXPECT_NE(run.out.find("--duration"), std::string::npos) << run.out;
}

// The demo towel with its corner grasped and carried over it (friction on the table, the fold's
// self-collision), the grasp spanning the save at 1 s.
BenchRun runDemoFold(const std::string& arguments) {
  return runShell(std::string(CLOTH_BENCH) + " --quiet --config " + PBD_CLOTH_SOURCE_DIR +
                  "/config/demo.yaml --set 'grippers.0.trajectory=["
                  "{t: 0.0, pose: [-0.2375, 0.2375, 0.406, 0, 0, 0, 1], grasp: true},"
                  "{t: 1.5, pose: [0.2, -0.2, 0.6, 0, 0, 0, 1]}]' " +
                  arguments);
}

TEST(ClothBench, SavedAndLoadedRunEqualsTheStraightRunBitForBit) {
  const std::string dir = ::testing::TempDir();
  const BenchRun straight = runDemoFold("--duration 2 --positions " + dir + "straight.csv" +
                                        " --save-state " + dir + "straight.state");
  ASSERT_EQ(straight.status, 0) << straight.out;
  const BenchRun first = runDemoFold("--duration 1 --positions " + dir + "half.csv" +
                                     " --save-state " + dir + "half.state");
  ASSERT_EQ(first.status, 0) << first.out;
  const BenchRun second =
      runDemoFold("--duration 1 --load-state " + dir + "half.state --positions " + dir +
                  "resumed.csv --save-state " + dir + "resumed.state");
  ASSERT_EQ(second.status, 0) << second.out;
  EXPECT_EQ(keyValues(second.out).at("sim_time"), "2");
  EXPECT_EQ(keyValues(second.out).at("steps"), "60");
  // Positions with max_digits10 digits, and the whole state, byte for byte.
  const std::string positions = readFile(dir + "straight.csv");
  EXPECT_EQ(std::count(positions.begin(), positions.end(), '\n'), 400);
  EXPECT_EQ(readFile(dir + "resumed.csv"), positions);
  EXPECT_NE(readFile(dir + "half.csv"), positions) << "the second second moved the cloth";
  const std::string state = readFile(dir + "straight.state");
  EXPECT_GT(state.size(), 400u * 2 * 3 * sizeof(double));
  EXPECT_TRUE(readFile(dir + "resumed.state") == state) << "state files differ";
}

TEST(ClothBench, StateThatDoesNotFitTheSceneExitsWithTwoAndTheReason) {
  const std::string dir = ::testing::TempDir();
  ASSERT_EQ(runDemoFold("--duration 0.1 --save-state " + dir + "fold.state --positions " + dir +
                        "fold.csv")
                .status,
            0);
  // Another cloth size: the particle count does not fit.
  BenchRun run =
      runDemoFold("--duration 0.1 --set cloth.rows=10 --load-state " + dir + "fold.state");
  EXPECT_EQ(run.status, 2);
  EXPECT_NE(run.out.find("--load-state"), std::string::npos) << run.out;
  EXPECT_NE(run.out.find("positions: 400 given, the scene has 200 particles"), std::string::npos)
      << run.out;
  // Another scene: the gripper is not there.
  run = runBench("--duration 0.1 --set cloth.rows=20 --set cloth.cols=20 --load-state " + dir +
                 "fold.state");
  EXPECT_EQ(run.status, 2);
  EXPECT_NE(run.out.find("grippers: 1 given, the scene has 0 grippers"), std::string::npos)
      << run.out;
  // Not a state file at all, and no file.
  run = runDemoFold("--duration 0.1 --load-state " + dir + "fold.csv");
  EXPECT_EQ(run.status, 2);
  EXPECT_NE(run.out.find("not a pbd_cloth state file"), std::string::npos) << run.out;
  run = runDemoFold("--duration 0.1 --load-state " + dir + "no_such.state");
  EXPECT_EQ(run.status, 2);
  EXPECT_NE(run.out.find("cannot read"), std::string::npos) << run.out;
}

// A scene with a robot URDF and a mesh obstacle, run from another working directory: the files
// are found relative to the scene file, load warnings go to stderr, a bad mesh stops the run.
TEST(ClothBench, RobotSceneFilesAreRelativeToTheSceneFile) {
  const std::string data = std::string(PBD_CLOTH_SOURCE_DIR) + "/test/data";
  const std::string bench =
      std::string("cd / && ") + CLOTH_BENCH + " --config " + data + "/robot_scene.yaml";
  BenchRun run = runShell(bench + " --quiet --duration 0.1");
  EXPECT_EQ(run.status, 0) << run.out;
  EXPECT_EQ(keyValues(run.out)["finite"], "1") << run.out;
  EXPECT_EQ(run.out.find("warning"), std::string::npos) << run.out;

  run = runShell(bench + " --quiet --duration 0.1 --set obstacles.0.mesh=open_square.obj");
  EXPECT_EQ(run.status, 0) << run.out;
  EXPECT_NE(run.out.find("warning: obstacles[0].mesh: mesh '" + data +
                         "/open_square.obj' has 4 open boundary edges"),
            std::string::npos)
      << run.out;

  run = runShell(bench + " --quiet --duration 0.1 --set robot.links=[body,elbow]");
  EXPECT_EQ(run.status, 2) << run.out;
  EXPECT_NE(run.out.find("robot.links[1]: no link 'elbow'"), std::string::npos) << run.out;

  run = runShell(bench + " --quiet --duration 0.1 --set obstacles.0.mesh=missing.stl");
  EXPECT_EQ(run.status, 2) << run.out;
  EXPECT_NE(run.out.find("obstacles[0].mesh: mesh file '" + data + "/missing.stl' not found"),
            std::string::npos)
      << run.out;
}

// The largest y of the particles in a --positions file (index,x,y,z lines).
double maxY(const std::string& positions_file) {
  std::istringstream lines(readFile(positions_file));
  std::string line;
  double max_y = -1e300;
  while (std::getline(lines, line)) {
    double index, x, y, z;
    if (std::sscanf(line.c_str(), "%lf,%lf,%lf,%lf", &index, &x, &y, &z) == 4) {
      max_y = std::max(max_y, y);
    }
  }
  return max_y;
}

// End to end through the URDF reader: a paddle link with a sphere, a box, a cylinder and a mesh,
// swept at 2 m/s through a hanging cloth by robot.joint_trajectory (forward kinematics), pushes it
// along (the cloth hangs in y = 0 without it) with no penetration beyond the thickness (5 mm).
TEST(ClothBench, UrdfRobotSweptThroughTheClothPushesItWithoutPenetration) {
  const std::string bench = std::string(CLOTH_BENCH) + " --config " + PBD_CLOTH_SOURCE_DIR +
                            "/test/data/robot_sweep.yaml --quiet --duration 0.7 --positions ";
  const std::string pushed = ::testing::TempDir() + "robot_sweep_positions.csv";
  const BenchRun run = runShell(bench + pushed);
  ASSERT_EQ(run.status, 0) << run.out;
  std::map<std::string, std::string> values = keyValues(run.out);
  EXPECT_EQ(values["finite"], "1") << run.out;
  EXPECT_LT(std::stod(values["max_penetration"]), 0.005) << run.out;
  // The paddle ends at y = 0.3; the cloth it carried is at least 0.2 m forward.
  EXPECT_GT(maxY(pushed), 0.2);

  // The same run with no link that collides (base_link has no collision element: a warning).
  const std::string alone = ::testing::TempDir() + "robot_sweep_positions_alone.csv";
  const BenchRun without = runShell(bench + alone + " --set 'robot.links=[base_link]'");
  ASSERT_EQ(without.status, 0) << without.out;
  EXPECT_NE(without.out.find("warning: robot.links[0]: link 'base_link' has no collision element"),
            std::string::npos)
      << without.out;
  EXPECT_LT(maxY(alone), 0.01);
}

// The search's answer meets the target, and one substep less at the same iterations does not:
// it is the cheapest of its column, not just some setting that meets.
TEST(ClothBench, TargetSearchFindsTheFewestSubstepsThatMeet) {
  const double target = 0.02;
  const BenchRun search =
      runBench("--duration 1 --target-max-strain " + std::to_string(target) + kSmallUntethered);
  ASSERT_EQ(search.status, 0) << search.out;
  const auto found = keyValues(search.out.substr(search.out.find("target_max_strain=")));
  ASSERT_EQ(found.at("met"), "1");
  const int substeps = std::stoi(found.at("substeps"));
  const int iterations = std::stoi(found.at("iterations"));
  EXPECT_LE(std::stod(found.at("max_strain")), target);
  EXPECT_NE(search.out.find("substeps: " + std::to_string(substeps)), std::string::npos)
      << "no YAML snippet: " << search.out;

  const auto rerun = [&](int s) {
    return keyValues(runBench("--duration 1 --set solver.substeps=" + std::to_string(s) +
                              " --set solver.iterations=" + std::to_string(iterations) +
                              kSmallUntethered)
                         .out);
  };
  EXPECT_LE(std::stod(rerun(substeps).at("max_strain")), target);
  if (substeps > 1) {
    EXPECT_GT(std::stod(rerun(substeps - 1).at("max_strain")), target);
  }
}

TEST(ClothBench, UnreachableTargetExitsWithThree) {
  const BenchRun run =
      runBench("--duration 0.5 --max-substeps 2 --target-max-strain 1e-9" + kSmallUntethered);
  EXPECT_EQ(run.status, 3) << run.out;
  EXPECT_NE(run.out.find("met=0"), std::string::npos) << run.out;
}

// The style rule of the package: every C++ file as the checked-in .clang-format formats it.
// clang-format is one of the packages scripts/setup_deps installs.
// Every shipped scene, config/*.yaml and the benchmark variants in config/bench/*.yaml, loads and
// runs in cloth_bench (three steps) and prints the strain of its final state and the medians over
// the last second.
TEST(ShippedScenes, EveryConfigRunsInClothBench) {
  const BenchRun listing = runShell(std::string("ls ") + PBD_CLOTH_SOURCE_DIR + "/config/*.yaml " +
                                    PBD_CLOTH_SOURCE_DIR + "/config/bench/*.yaml");
  ASSERT_EQ(listing.status, 0) << listing.out;
  std::istringstream lines(listing.out);
  std::vector<std::string> paths;
  for (std::string path; std::getline(lines, path);) paths.push_back(path);
  EXPECT_GE(paths.size(), 20u) << listing.out;
  EXPECT_NE(listing.out.find("/config/held_corners.yaml"), std::string::npos);
  EXPECT_NE(listing.out.find("/config/bench/held_100_2pct.yaml"), std::string::npos);
  for (const std::string& path : paths) {
    const BenchRun run =
        runShell(std::string(CLOTH_BENCH) + " --config " + path + " --duration 0.05 --quiet");
    ASSERT_EQ(run.status, 0) << path << "\n" << run.out;
    const auto values = keyValues(run.out);
    EXPECT_EQ(values.at("finite"), "1") << path;
    for (const char* key :
         {"final_structural_max_strain", "final_structural_mean_strain",
          "median_structural_max_strain_last_1s", "median_structural_mean_strain_last_1s"}) {
      ASSERT_EQ(values.count(key), 1u) << path << ": " << key;
      EXPECT_TRUE(std::isfinite(std::stod(values.at(key)))) << path << ": " << key;
    }
  }
}

#ifdef BULLET_CLOTH_BENCH
// bullet_cloth_bench holds what a gripper grasps at t = 0 as moving pins: the corners of
// config/held_corners.yaml are where the grippers put them, halfway along their 0.1 s move at
// 0.05 s and at its end afterwards, as in cloth_bench; and every config/bench/ scene runs.
TEST(BulletClothBench, GrippersGraspingAtTheStartHoldTheirParticlesOnTheirTrajectories) {
  const std::string positions = ::testing::TempDir() + "bullet_held.csv";
  for (const double duration : {0.05, 0.5}) {
    const BenchRun run = runShell(
        std::string(BULLET_CLOTH_BENCH) + " --config " + PBD_CLOTH_SOURCE_DIR +
        "/config/held_corners.yaml --duration " + std::to_string(duration) +
        " --set bullet.substeps=4 --set bullet.piterations=2" + " --positions " + positions);
    ASSERT_EQ(run.status, 0) << run.out;
    EXPECT_EQ(keyValues(run.out).at("grasped_particles"), "2") << run.out;
    EXPECT_EQ(run.out.find("not simulated"), std::string::npos) << run.out;
    std::istringstream lines(readFile(positions));
    std::map<int, std::array<double, 3>> at;
    for (std::string line; std::getline(lines, line);) {
      std::array<double, 3> x{};
      int index = -1;
      if (std::sscanf(line.c_str(), "%d,%lf,%lf,%lf", &index, &x[0], &x[1], &x[2]) == 4) {
        at[index] = x;
      }
    }
    ASSERT_EQ(at.size(), 2500u);
    const double inward = duration < 0.1 ? 0.00125 : 0.0025;  // m, each corner
    EXPECT_NEAR(at[0][0], inward, 1e-6) << duration;          // single precision: 1e-7 m at 1 m
    EXPECT_NEAR(at[49][0], 1.0 - inward, 1e-6) << duration;
    for (int corner : {0, 49}) {
      EXPECT_NEAR(at[corner][1], 0.0, 1e-6) << corner;
      EXPECT_NEAR(at[corner][2], 1.5, 1e-6) << corner;
    }
    if (duration > 0.1) {
      EXPECT_LT(at[2450][2], 1.0) << "the free corners swing down";
    }
  }
  const BenchRun listing =
      runShell(std::string("ls ") + PBD_CLOTH_SOURCE_DIR + "/config/bench/held_*.yaml " +
               PBD_CLOTH_SOURCE_DIR + "/config/held_corners.yaml " + PBD_CLOTH_SOURCE_DIR +
               "/config/tshirt_held.yaml");  // the scenes whose grippers grasp at t = 0
  std::istringstream lines(listing.out);
  for (std::string path; std::getline(lines, path);) {
    const BenchRun run =
        runShell(std::string(BULLET_CLOTH_BENCH) + " --config " + path + " --duration 0.05" +
                 " --quiet --set bullet.substeps=2 --set bullet.piterations=1");
    ASSERT_EQ(run.status, 0) << path << "\n" << run.out;
    const auto values = keyValues(run.out);
    EXPECT_EQ(values.at("finite"), "1") << path;
    EXPECT_NE(values.at("grasped_particles"), "0") << path;
    EXPECT_TRUE(std::isfinite(std::stod(values.at("median_structural_mean_strain_last_1s"))))
        << path;
  }
}
#endif

TEST(SourceStyle, EveryCppFileIsClangFormatted) {
  const BenchRun run = runShell(std::string("cd '") + PBD_CLOTH_SOURCE_DIR +
                                "' && find -L src include test \\( -name '*.cpp' -o -name '*.h' \\)"
                                " -print0 | xargs -0 clang-format --dry-run --Werror");
  EXPECT_EQ(run.status, 0) << "not clang-formatted (run clang-format -i on these):\n"
                           << run.out.substr(0, 4000);
}

// The rules of the house (doc/design.md): every #include of src/ and include/ keeps to the layering
// (geometry below model below constraints and collision below solver below sim; the configuration
// seen only from sim/; the core on Eigen and std alone; intrinsics only in kernel files).
TEST(SourceStyle, EveryIncludeKeepsTheRulesOfTheHouse) {
  const BenchRun run = runShell(std::string("/usr/bin/python3 '") + PBD_CLOTH_SOURCE_DIR +
                                "/scripts/check_includes' '" + PBD_CLOTH_SOURCE_DIR + "'");
  EXPECT_EQ(run.status, 0) << run.out;
  EXPECT_NE(run.out.find(" 0 forbidden includes"), std::string::npos) << run.out;
}

// The checker itself fails on a forbidden include: a copy of the sources where geometry/ includes
// the scene configuration and the core includes ROS.
TEST(SourceStyle, TheIncludeCheckFailsOnAForbiddenInclude) {
  char pattern[] = "/tmp/pbd_include_rules.XXXXXX";
  ASSERT_NE(mkdtemp(pattern), nullptr);
  const std::string copy = pattern;
  const std::string source = PBD_CLOTH_SOURCE_DIR;
  ASSERT_EQ(runShell("cp -rL '" + source + "/src' '" + source + "/include' '" + copy + "/'").status,
            0);
  {
    std::ofstream shape(copy + "/include/pbd_cloth/geometry/shapes.h", std::ios::app);
    shape << "#include \"pbd_cloth/config/scene_config.h\"\n";
    std::ofstream solver(copy + "/src/core/solver/solver.cpp", std::ios::app);
    solver << "#include <ros/ros.h>\n";
  }
  const BenchRun run =
      runShell("/usr/bin/python3 '" + source + "/scripts/check_includes' '" + copy + "'");
  runShell("rm -rf '" + copy + "'");
  EXPECT_EQ(run.status, 1) << run.out;
  EXPECT_NE(run.out.find("include/pbd_cloth/geometry/shapes.h"), std::string::npos) << run.out;
  EXPECT_NE(run.out.find("geometry/ may include only geometry (not config/)"), std::string::npos)
      << run.out;
  EXPECT_NE(run.out.find("src/core/solver/solver.cpp"), std::string::npos) << run.out;
  EXPECT_NE(run.out.find("not <ros/ros.h>"), std::string::npos) << run.out;
}

// The shipped STL meshes (config/meshes, urdf/meshes) are closed, outward and of their analytic
// volume, and are exactly the bytes scripts/make_meshes writes: regenerated, not hand-edited.
TEST(ShippedMeshes, AreClosedAndWhatMakeMeshesWrites) {
  const BenchRun run = runShell(std::string("/usr/bin/python3 '") + PBD_CLOTH_SOURCE_DIR +
                                "/scripts/make_meshes' --compare");
  EXPECT_EQ(run.status, 0) << run.out;
  EXPECT_NE(run.out.find("urdf/meshes/palm.stl"), std::string::npos) << run.out;
}

}  // namespace
