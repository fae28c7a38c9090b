#pragma once
/// @file
/// The one way HexMerge spreads work over threads: fixed-size chunks of an index range, taken in
/// turn by the calling thread and the workers.

#include <algorithm>
#include <atomic>
#include <exception>
#include <mutex>
#include <string>
#include <system_error>
#include <thread>
#include <utility>
#include <vector>

#include "hexmerge/core/error.h"
#include "hexmerge/core/index.h"

namespace hexmerge {

/// Starts a thread running fn; when the system cannot start one (too many threads for the
/// address space or the process limits), throws ResourceError naming the parameter `threads`
/// instead of std::system_error.
/// @param[in] number   the thread's number among those asked for (1-based), for the message
/// @param[in] asked    how many threads the run asked for, for the message
template <class Fn>
std::thread start_thread(int number, int asked, Fn&& fn) {
  try {
    return std::thread(std::forward<Fn>(fn));
  } catch (const std::system_error& e) {
    throw ResourceError("could not start thread " + std::to_string(number) + " of the " +
                        std::to_string(asked) + " asked for by the parameter threads (" + e.what() +
                        "): give fewer threads");
  }
}

/// The number of threads the parameter `threads` asks for: itself when positive, else (0) every
/// hardware thread (1 when the system cannot tell).
inline int thread_count(int requested) {
  if (requested > 0) return requested;
  const unsigned hw = std::thread::hardware_concurrency();
  return hw == 0 ? 1 : static_cast<int>(hw);
}

/// Runs work(chunk, begin, end) for the chunks [begin, end) of [0, n) of `chunk_size` items, on
/// `threads` threads (the calling thread included; at least 1).
///
/// After each chunk the calling thread finishes, it calls done(fraction of chunks finished);
/// when that returns false the remaining chunks are skipped and Cancelled is thrown once every
/// thread has stopped. `work` must only write to its own chunk's data. An exception thrown by
/// `work` on any thread (std::bad_alloc included) stops the other threads and is rethrown here,
/// on the calling thread; a thread that cannot be started throws ResourceError the same way
/// (never a silent run on fewer threads).
template <class Work, class Done>
void parallel_chunks(index_t n, index_t chunk_size, int threads, const Work& work,
                     const Done& done) {
  const index_t nb_chunks = (n + chunk_size - 1) / chunk_size;
  std::atomic<index_t> next{0}, finished{0};
  std::atomic<bool> cancelled{false}, stop{false};
  std::mutex error_mutex;
  std::exception_ptr error;
  auto fail = [&](std::exception_ptr e) {
    const std::lock_guard<std::mutex> lock(error_mutex);
    if (!error) error = std::move(e);
    stop = true;
  };
  auto run = [&](bool reports) {
    try {
      for (index_t chunk; !stop.load() && (chunk = next.fetch_add(1)) < nb_chunks;) {
        work(chunk, chunk * chunk_size, std::min(n, (chunk + 1) * chunk_size));
        const index_t count = ++finished;
        if (reports && !done(static_cast<double>(count) / nb_chunks)) {
          cancelled = true;
          stop = true;
        }
      }
    } catch (...) {
      fail(std::current_exception());
    }
  };
  std::vector<std::thread> pool;
  const int asked = std::max(1, threads);
  try {
    pool.reserve(static_cast<std::size_t>(asked - 1));
    for (int i = 1; i < asked; ++i) pool.push_back(start_thread(i + 1, asked, [&] { run(false); }));
  } catch (...) {
    fail(std::current_exception());
  }
  run(true);
  for (auto& th : pool) th.join();
  if (error) std::rethrow_exception(error);
  if (cancelled) throw Cancelled();
}

/// parallel_chunks without progress.
template <class Work>
void parallel_chunks(index_t n, index_t chunk_size, int threads, const Work& work) {
  parallel_chunks(n, chunk_size, threads, work, [](double) { return true; });
}

/// Concatenates per-chunk results in chunk order (so the result does not depend on the number
/// of threads), freeing each chunk as it goes.
template <class T>
std::vector<T> concatenate(std::vector<std::vector<T>>& per_chunk) {
  std::size_t total = 0;
  for (const auto& c : per_chunk) total += c.size();
  std::vector<T> all;
  all.reserve(total);
  for (auto& c : per_chunk) {
    all.insert(all.end(), c.begin(), c.end());
    std::vector<T>().swap(c);
  }
  return all;
}

}  // namespace hexmerge
