#include "pbd_cloth/parallel/worker_pool.h"

namespace pbd_cloth {

namespace {

// About 20-50 us of spinning on this machine kind: longer than the gaps between the jobs of one
// substep, much shorter than the wait for the next step of a 60 Hz node.
constexpr int kSpins = 20000;

inline void relax() {
#if defined(__x86_64__) && defined(__GNUC__)
  __builtin_ia32_pause();  // the PAUSE spin-wait hint (_mm_pause), without the intrinsics header
#else
  std::this_thread::yield();
#endif
}

}  // namespace

void WorkerPool::resize(int threads) {
  if (threads < 1) threads = 1;
  if (threads == this->threads()) return;
  if (!workers_.empty()) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stop_.store(true);
      generation_.fetch_add(1);
    }
    wake_.notify_all();
    for (std::thread& worker : workers_) worker.join();
    workers_.clear();
    stop_.store(false);
  }
  open_ = std::make_unique<std::atomic<std::uint64_t>[]>(static_cast<std::size_t>(threads));
  for (int t = 1; t < threads; ++t) open_[t - 1].store(0);
  for (int t = 1; t < threads; ++t) workers_.emplace_back(&WorkerPool::work, this, t);
}

bool WorkerPool::claim(int t, std::uint64_t generation) {
  std::uint64_t expected = generation;
  // Acquire: the job's call and context, stored before the index was opened, are this
  // generation's. The caller waits for pending_ before it opens the next, so they stay so while
  // the index runs.
  if (!open_[t - 1].compare_exchange_strong(expected, 0, std::memory_order_acq_rel)) return false;
  call_(context_, t);
  pending_.fetch_sub(1, std::memory_order_acq_rel);
  return true;
}

void WorkerPool::dispatch(Call call, void* context) {
  call_ = call;
  context_ = context;
  const int workers = static_cast<int>(workers_.size());
  pending_.store(workers, std::memory_order_relaxed);
  const std::uint64_t generation = generation_.load(std::memory_order_relaxed) + 1;
  for (int t = 1; t <= workers; ++t) open_[t - 1].store(generation, std::memory_order_release);
  {
    // Under the mutex, so a worker between its last check and its wait cannot miss the change.
    std::lock_guard<std::mutex> lock(mutex_);
    generation_.store(generation, std::memory_order_release);
  }
  if (sleeping_.load(std::memory_order_acquire) > 0) wake_.notify_all();
  call(context, 0);
  // The indices no worker has claimed yet: run here rather than wait for a worker to wake.
  for (int t = 1; t <= workers; ++t) claim(t, generation);
  for (int spin = 0; pending_.load(std::memory_order_acquire) > 0; ++spin) {
    if (spin < kSpins) {
      relax();
    } else {
      std::this_thread::yield();  // a worker was descheduled: let it run
    }
  }
}

void WorkerPool::work(int index) {
  std::uint64_t seen = 0;
  while (true) {
    std::uint64_t now = generation_.load(std::memory_order_acquire);
    for (int spin = 0; now == seen && spin < kSpins; ++spin) {
      relax();
      now = generation_.load(std::memory_order_acquire);
    }
    if (now == seen) {
      std::unique_lock<std::mutex> lock(mutex_);
      sleeping_.fetch_add(1, std::memory_order_acq_rel);
      wake_.wait(lock, [&] { return generation_.load(std::memory_order_acquire) != seen; });
      sleeping_.fetch_sub(1, std::memory_order_acq_rel);
      now = generation_.load(std::memory_order_acquire);
    }
    seen = now;
    if (stop_.load(std::memory_order_acquire)) return;
    // Nothing to do if the caller took the index already, or if a later job has begun since
    // `now` was read (then the next turn of the loop sees it).
    claim(index, now);
  }
}

}  // namespace pbd_cloth
