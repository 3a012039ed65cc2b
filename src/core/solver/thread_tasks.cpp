// solver.threads: which thread runs which tasks of each phase of the stretch links.
#include "pbd_cloth/solver/solver.h"

namespace pbd_cloth {

// Each phase's tasks cut into solver.threads contiguous ranges of about equal link counts. Which
// thread runs which task changes nothing in the result (the tasks of a phase are independent).
void Solver::splitTasks() {
  const int threads = pool_.threads();
  thread_results_.assign(threads, StretchPassResult());
  thread_tasks_.clear();
  for (int phase = 0; phase < stretch_links_.phaseCount(); ++phase) {
    const int first = stretch_links_.phase_task[phase], end = stretch_links_.phase_task[phase + 1];
    long total = 0;
    for (int t = first; t < end; ++t) total += stretch_links_.taskLinks(t);
    thread_tasks_.push_back(first);
    long done = 0;
    int task = first;
    for (int t = 1; t < threads; ++t) {
      // Thread t - 1 takes tasks until its share of the links (t / threads of the total) is met.
      // A task goes to this thread when its middle lies within the thread's share.
      while (task < end && (2 * done + stretch_links_.taskLinks(task)) * threads <= 2 * t * total) {
        done += stretch_links_.taskLinks(task);
        ++task;
      }
      thread_tasks_.push_back(task);
    }
    thread_tasks_.push_back(end);
  }
}

}  // namespace pbd_cloth
