// Whether the next step runs on all of solver.threads or on the calling thread alone
// (solver.adaptive_threads), chosen from the steps' own wall times.
//
// Why: two threads gain only while both have a core. On a robot's computer other nodes take
// cores, and a worker that the scheduler takes off its core in the middle of its share keeps the
// calling thread waiting for the rest of that share until it runs again; on this project's
// two-core machine, with a busy loop beside it, fabric_table took 0.52-0.68 ms a step on two
// threads against 0.50-0.51 ms on one (doc/journal.md, "2026-11-29: Threads beside a busy process:
// `solver.adaptive_threads`"). The partition of the work into tasks does not change with the choice
// (WorkerPool::setSolo runs every index of a job on the calling thread, in order), so results stay
// bit-identical whichever is chosen, and the choice may change at any step.
//
// How: the step runs in its preferred mode and now and then, for kProbeSteps steps, in the other
// one (the first of them a warm-up: workers asleep after a solo stretch wake up, caches refill).
// The other mode takes over when its measured steps averaged kSwitchMargin less than the last
// kHistory steps of the preferred one; a probe step over kAbortFactor times that ends the probe. A
// probe that confirms the preferred mode doubles the interval to the next (kFirstInterval up to
// kLongestInterval steps), so a settled choice costs about kProbeSteps / kLongestInterval of the
// steps in the slower mode. Allocates nothing.
#pragma once

namespace pbd_cloth {

class ThreadChoice {
 public:
  static constexpr int kHistory = 4;            // preferred-mode steps the probe is compared with
  static constexpr int kProbeSteps = 3;         // steps of the other mode, the first not counted
  static constexpr int kFirstInterval = 4;      // preferred-mode steps before the first probe
  static constexpr int kLongestInterval = 512;  // and at most between two probes
  static constexpr double kSwitchMargin = 0.05;
  // A probe step (the warm-up included) longer than this times the history's mean ends the probe
  // at once: the other mode is not faster, and beside a busy process a step on all threads can
  // take four times one on the calling thread, so a probe's later steps would only cost.
  static constexpr double kAbortFactor = 2.0;

  // Starts again in `solo` (false: all threads), with no history.
  void reset(bool solo = false);
  // The mode of the next step, given the wall time (s) of the step just run in the mode this
  // returned last. A non-finite or negative time is not counted.
  bool next(double step_seconds);

  bool solo() const { return current_solo_; }
  bool preferredSolo() const { return preferred_solo_; }
  int switches() const { return switches_; }  // changes of the preferred mode since reset
  int probes() const { return probes_; }      // probes finished since reset

 private:
  double historyMean() const;

  bool preferred_solo_ = false;
  bool current_solo_ = false;
  double history_[kHistory] = {};
  int history_count_ = 0;  // up to kHistory
  int history_next_ = 0;   // ring position of the next entry
  int interval_ = kFirstInterval;
  int until_probe_ = kFirstInterval;
  int probe_step_ = -1;  // steps of the probe run so far; -1: not probing
  double probe_sum_ = 0.0;
  int probe_counted_ = 0;
  // The first step after reset() or after a probe: a warm-up (cold caches, sleeping workers), not
  // counted.
  bool skip_next_ = true;  // on fabric_table a first step took 0.66-0.75 ms, the next 0.43
  int switches_ = 0;
  int probes_ = 0;
};

}  // namespace pbd_cloth
