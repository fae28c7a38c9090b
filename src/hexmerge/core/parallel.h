#pragma once
/// @file
/// The one way HexMerge spreads work over threads: fixed-size chunks of an index range, taken in
/// turn by the calling thread and the workers.

#include <algorithm>
#include <atomic>
#include <thread>
#include <vector>

#include "hexmerge/core/error.h"
#include "hexmerge/core/index.h"

namespace hexmerge {

/// Runs work(chunk, begin, end) for the chunks [begin, end) of [0, n) of `chunk_size` items, on
/// `threads` threads (the calling thread included; at least 1).
///
/// After each chunk the calling thread finishes, it calls done(fraction of chunks finished);
/// when that returns false the remaining chunks are skipped and Cancelled is thrown once every
/// thread has stopped. `work` must only write to its own chunk's data.
template <class Work, class Done>
void parallel_chunks(index_t n, index_t chunk_size, int threads, const Work& work,
                     const Done& done) {
  const index_t nb_chunks = (n + chunk_size - 1) / chunk_size;
  std::atomic<index_t> next{0}, finished{0};
  std::atomic<bool> cancelled{false};
  auto run = [&](bool reports) {
    for (index_t chunk; !cancelled.load() && (chunk = next.fetch_add(1)) < nb_chunks;) {
      work(chunk, chunk * chunk_size, std::min(n, (chunk + 1) * chunk_size));
      const index_t count = ++finished;
      if (reports && !done(static_cast<double>(count) / nb_chunks)) cancelled = true;
    }
  };
  std::vector<std::thread> pool;
  for (int i = 1; i < std::max(1, threads); ++i) pool.emplace_back(run, false);
  run(true);
  for (auto& th : pool) th.join();
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
