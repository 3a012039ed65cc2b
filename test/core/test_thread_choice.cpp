// solver.adaptive_threads (thread_choice.h): the choice between all threads and the calling thread
// alone follows the measured step times, probes the other mode rarely once settled, and never
// changes the results (the work's partition stays that of solver.threads).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <thread>
#include <vector>

#include "pbd_cloth/parallel/thread_choice.h"
#include "pbd_cloth/parallel/worker_pool.h"
#include "pbd_cloth/sim/simulation.h"
#include "test_scenes.h"

namespace pbd_cloth {
namespace {

// Steps `steps` times a machine where a step takes `threads_ms` on all threads and `solo_ms` on
// the calling thread alone; returns the mode of every step run.
std::vector<bool> runSteps(ThreadChoice& choice, int steps, double threads_ms, double solo_ms) {
  std::vector<bool> solo;
  for (int k = 0; k < steps; ++k) {
    solo.push_back(choice.solo());
    choice.next(1e-3 * (choice.solo() ? solo_ms : threads_ms));
  }
  return solo;
}

int count(const std::vector<bool>& modes, bool value, int from = 0) {
  int n = 0;
  for (std::size_t k = from; k < modes.size(); ++k) n += modes[k] == value ? 1 : 0;
  return n;
}

// Threads faster (no other process on the cores): the choice stays with them; its probes of the
// calling thread alone (kProbeSteps each) come at doubling intervals, so after the first 1000
// steps they take under 1 % of the steps.
TEST(ThreadChoice, StaysWithThreadsWhileTheyAreFaster) {
  ThreadChoice choice;
  const std::vector<bool> modes = runSteps(choice, 4000, 1.0, 1.6);
  EXPECT_EQ(choice.switches(), 0);
  EXPECT_FALSE(choice.preferredSolo());
  // The first probe comes once the history is full: steps 5, 6 and 7 (from 0; the first step, on
  // cold caches, is not counted).
  const int first = ThreadChoice::kHistory + 1;
  for (int k = 0; k < first; ++k) EXPECT_FALSE(modes[k]) << k;
  for (int k = 0; k < ThreadChoice::kProbeSteps; ++k) EXPECT_TRUE(modes[first + k]) << k;
  EXPECT_FALSE(modes[first + ThreadChoice::kProbeSteps]);
  // Intervals 4, 8, ..., 512, then 512 each: 7 probes by step 1000, one each 515 steps after.
  EXPECT_EQ(count(modes, true), choice.probes() * ThreadChoice::kProbeSteps);
  EXPECT_GE(choice.probes(), 12);
  EXPECT_LE(choice.probes(), 14);
  EXPECT_LT(count(modes, true, 1000), 0.01 * 3000);
}

// Another process holds a core: a step on all threads takes twice the calling thread's. The choice
// goes to the calling thread at the first probe and stays there, trying the threads rarely.
TEST(ThreadChoice, GoesToTheCallingThreadWhenThatIsFaster) {
  ThreadChoice choice;
  const std::vector<bool> modes = runSteps(choice, 4000, 2.0, 1.0);
  EXPECT_TRUE(choice.preferredSolo());
  EXPECT_EQ(choice.switches(), 1);
  const int first = ThreadChoice::kHistory + 1;
  EXPECT_TRUE(modes[first]);  // the first probe, and from there on the calling thread
  EXPECT_GT(count(modes, true, first), 0.98 * (4000 - first));
}

// The core comes free again: the next probe of the threads finds them faster and takes them back.
TEST(ThreadChoice, ReturnsToTheThreadsWhenTheCoreIsFreeAgain) {
  ThreadChoice choice;
  runSteps(choice, 600, 2.0, 1.0);
  ASSERT_TRUE(choice.preferredSolo());
  const std::vector<bool> modes = runSteps(choice, 1200, 0.6, 1.0);
  EXPECT_FALSE(choice.preferredSolo());
  EXPECT_EQ(choice.switches(), 2);
  // Within one longest interval and a probe of the change, then on the threads.
  EXPECT_GT(count(modes, false), 1200 - ThreadChoice::kLongestInterval - 40);
}

// Within the margin (5 %) the choice keeps what it has: no switching back and forth on noise.
TEST(ThreadChoice, ADifferenceWithinTheMarginChangesNothing) {
  ThreadChoice choice;
  runSteps(choice, 3000, 1.0, 0.97);
  EXPECT_EQ(choice.switches(), 0);
  ThreadChoice other;
  runSteps(other, 3000, 1.0, 1.03);
  EXPECT_EQ(other.switches(), 0);
}

// A probe's first step is a warm-up (workers waking from sleep), and a time that is not a number
// (a broken clock) is not counted: neither decides the choice.
TEST(ThreadChoice, WarmUpAndNonFiniteTimesAreNotCounted) {
  ThreadChoice choice;
  choice.next(50e-3);  // the first step: cold caches, not counted
  for (int k = 0; k < ThreadChoice::kHistory; ++k) choice.next(2e-3);  // threads
  ASSERT_TRUE(choice.solo());                                          // the probe begins
  choice.next(3e-3);  // warm-up: slower than the threads, not counted
  choice.next(std::numeric_limits<double>::quiet_NaN());
  choice.next(1e-3);                    // the only counted probe step: half the threads' time
  EXPECT_TRUE(choice.preferredSolo());  // counted, the warm-up would have made it 2 ms: no switch
  EXPECT_EQ(choice.probes(), 1);
  ThreadChoice nan_only;
  for (int k = 0; k < 40; ++k) nan_only.next(std::numeric_limits<double>::quiet_NaN());
  EXPECT_EQ(nan_only.probes(), 0);  // no history, no probe
  EXPECT_FALSE(nan_only.solo());
}

// A probe step over twice the history's mean (a step on all threads beside a busy process) ends
// the probe at once: the other mode is not faster, and its next steps would only cost.
TEST(ThreadChoice, AProbeStepOverTwiceTheHistoryEndsTheProbe) {
  ThreadChoice choice;
  runSteps(choice, 100, 2.0, 1.0);
  ASSERT_TRUE(choice.preferredSolo());
  // The next probe of the threads: its first step takes five times the calling thread's.
  int steps = 0;
  while (choice.solo() && steps < 1000) {
    choice.next(1e-3);
    ++steps;
  }
  ASSERT_FALSE(choice.solo());
  const int probes = choice.probes();
  choice.next(5e-3);
  EXPECT_TRUE(choice.solo());  // back at once, after one step
  EXPECT_EQ(choice.probes(), probes + 1);
  EXPECT_TRUE(choice.preferredSolo());
}

// Solo: every index of a job runs on the calling thread, in order, once; the workers run none.
TEST(WorkerPool, SoloRunsEveryIndexOnTheCallingThreadInOrder) {
  WorkerPool pool;
  pool.resize(3);
  pool.setSolo(true);
  ASSERT_TRUE(pool.solo());
  ASSERT_EQ(pool.threads(), 3);  // the partition stays that of three threads
  const std::thread::id caller = std::this_thread::get_id();
  for (int run = 0; run < 100; ++run) {
    std::vector<int> order;
    std::vector<std::thread::id> ran_on;
    auto job = [&](int t) {
      order.push_back(t);
      ran_on.push_back(std::this_thread::get_id());
    };
    pool.run(job);
    ASSERT_EQ(order, (std::vector<int>{0, 1, 2}));
    for (const std::thread::id& id : ran_on) ASSERT_EQ(id, caller);
  }
  pool.setSolo(false);
  std::vector<int> calls(3, 0);
  auto job = [&](int t) { ++calls[t]; };
  for (int run = 0; run < 100; ++run) pool.run(job);
  EXPECT_EQ(calls, (std::vector<int>{100, 100, 100}));
}

// The solver with solver.adaptive_threads: whichever thread runs a step, the cloth is the one
// of a single thread, bit for bit. The first probe (from step 5, after four steps of history) runs
// on the calling thread alone whatever the times, so both modes run here.
TEST(ThreadChoice, EveryStepsThreadsGiveTheSameCloth) {
  SceneConfig scene = test::clothScene(40, 40, 0.025, Method::kXpbd);
  scene.cloth.pinned = {0, 39};
  scene.cloth.bend_compliance = 1e-3;
  scene.solver.substeps = 8;
  scene.solver.threads = 1;
  Simulation single(scene);
  scene.solver.threads = 2;
  scene.solver.adaptive_threads = true;
  Simulation adaptive(scene);
  int solo_steps = 0, threaded_steps = 0;
  for (int step = 0; step < 40; ++step) {
    single.step();
    adaptive.step();
    EXPECT_EQ(adaptive.solver().stats().on_one_thread, adaptive.solver().stats().threads_used == 1);
    if (adaptive.solver().stats().threads_used == 1) {
      ++solo_steps;
    } else {
      EXPECT_EQ(adaptive.solver().stats().threads_used, 2);
      ++threaded_steps;
    }
  }
  EXPECT_GE(solo_steps, 1);
  EXPECT_GE(threaded_steps, ThreadChoice::kHistory);
  EXPECT_EQ(adaptive.particles().position, single.particles().position);
  EXPECT_GT(
      (single.particles().position[1599] - Simulation(scene).particles().position[1599]).norm(),
      0.1);
  // Off: every step on both threads.
  scene.solver.adaptive_threads = false;
  Simulation fixed(scene);
  for (int step = 0; step < 20; ++step) {
    fixed.step();
    EXPECT_EQ(fixed.solver().stats().threads_used, 2);
    EXPECT_FALSE(fixed.solver().stats().on_one_thread);
  }
}

}  // namespace
}  // namespace pbd_cloth
