// A fixed set of worker threads for the solver step (solver.threads): run(job) calls job(t) once
// for every t in [0, threads), the calling thread taking t = 0, and returns when all are done;
// runRanges(count, range) does the same over equal consecutive ranges of count items.
// Which work each t does is the caller's fixed partition, so results never depend on timing.
//
// Workers spin briefly between jobs (a substep syncs a few times within microseconds), then sleep
// on a condition variable, so an idle node between steps costs no processor time. run() allocates
// nothing: the job is passed as a function pointer and a context.
//
// Each index is claimed before it runs, by its worker or, once the calling thread has done index
// 0, by the caller: a worker that has not woken by then (it slept through a long serial part of
// the step, such as a garment's self-contacts) no longer holds the caller up for its wake-up, which
// costs more than a small job itself (on the T-shirt, two threads, 4.4 % of the samples were the
// caller waiting here: doc/journal.md, "2026-11-28: A worker's share run by the caller, and a
// resize that crashed"). Which work an index does never changes, only which thread runs it, and the
// indices of one job are independent by contract, so results stay the same. A worker runs only an
// index opened for the generation it saw, so one started by a new thread count does not run the
// last job again.
//
// Solo (setSolo, solver.adaptive_threads: thread_choice.h): the calling thread runs every index of
// each job itself, in order, and the workers are not woken (they sleep after their spin). The
// indices, and so the work each does, are those of threads(): the results are those of the pool.
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

namespace pbd_cloth {

class WorkerPool {
 public:
  WorkerPool() = default;
  ~WorkerPool() { resize(1); }
  WorkerPool(const WorkerPool&) = delete;
  WorkerPool& operator=(const WorkerPool&) = delete;

  // Starts or stops workers so that `threads` (>= 1) run each job, the caller included.
  void resize(int threads);
  int threads() const { return static_cast<int>(workers_.size()) + 1; }
  // The first of `count` items that t of `threads` takes when they split them into equal
  // consecutive ranges: t takes [rangeBegin(count, t, threads), rangeBegin(count, t + 1, threads)).
  static int rangeBegin(int count, int t, int threads) {
    return static_cast<int>(static_cast<long>(count) * t / threads);
  }

  // Splits [0, count) into one range a thread (rangeBegin) and calls range(begin, end, t) on
  // thread t: which items a thread takes depends only on count and the thread count.
  template <typename Range>
  void runRanges(int count, Range&& range) {
    const int n = threads();
    auto job = [&](int t) { range(rangeBegin(count, t, n), rangeBegin(count, t + 1, n), t); };
    run(job);
  }

  // Solo: the next jobs run every index on the calling thread (see the top of this file).
  void setSolo(bool solo) { solo_ = solo; }
  bool solo() const { return solo_ || workers_.empty(); }

  template <typename Job>
  void run(Job& job) {
    if (solo()) {
      const int n = threads();
      for (int t = 0; t < n; ++t) job(t);
      return;
    }
    dispatch([](void* context, int t) { (*static_cast<Job*>(context))(t); }, &job);
  }

 private:
  using Call = void (*)(void*, int);
  void dispatch(Call call, void* context);
  void work(int index);

  // Runs index t of the current job if it is still open for `generation`; true if it ran it.
  bool claim(int t, std::uint64_t generation);

  std::vector<std::thread> workers_;
  // open_[t - 1]: the generation whose index t nobody has claimed yet (0: claimed or none).
  std::unique_ptr<std::atomic<std::uint64_t>[]> open_;
  std::atomic<std::uint64_t> generation_{0};
  std::atomic<int> pending_{0};
  std::atomic<int> sleeping_{0};
  std::atomic<bool> stop_{false};
  bool solo_ = false;
  Call call_ = nullptr;
  void* context_ = nullptr;
  std::mutex mutex_;
  std::condition_variable wake_;
};

}  // namespace pbd_cloth
