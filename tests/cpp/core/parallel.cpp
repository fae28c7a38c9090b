// parallel_chunks: an exception on any thread reaches the caller; a thread the system cannot start
// is reported, never a crash nor a silent run on fewer threads.
#include "hexmerge/core/parallel.h"

#include <gtest/gtest.h>
#include <sys/resource.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <new>
#include <string>
#include <thread>

#if defined(__SANITIZE_ADDRESS__)
#define HEXMERGE_TEST_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define HEXMERGE_TEST_ASAN 1
#endif
#endif

namespace hexmerge {
namespace {

// Throws `error` from every chunk run on a worker thread (the calling thread only sleeps, so the
// workers take chunks too).
template <class Error>
void throw_on_workers(const Error& error) {
  const std::thread::id caller = std::this_thread::get_id();
  parallel_chunks(200, 1, 4, [&](index_t, index_t, index_t) {
    if (std::this_thread::get_id() != caller) throw error;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  });
}

TEST(ParallelChunks, RethrowsAWorkersInputErrorOnTheCallingThread) {
  try {
    throw_on_workers(InputError("element 7 is bad", Entity::Element, 7));
    FAIL() << "no exception";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), "element 7 is bad");
    EXPECT_EQ(e.id(), 7u);
  }
}

TEST(ParallelChunks, RethrowsAWorkersBadAllocOnTheCallingThread) {
  EXPECT_THROW(throw_on_workers(std::bad_alloc()), std::bad_alloc);
}

TEST(ParallelChunks, StopsTheOtherChunksAfterAnError) {
  // Every other chunk takes 0.2 ms, so that the thread not throwing cannot run through all of
  // them before the error reaches it (with chunks of no work it sometimes did on a loaded
  // machine: the test failed though the stop worked). Without the stop, all 2000 would run.
  std::atomic<int> ran{0};
  EXPECT_THROW(parallel_chunks(2000, 1, 2,
                               [&](index_t chunk, index_t, index_t) {
                                 ++ran;
                                 if (chunk == 10) throw InputError("stop");
                                 std::this_thread::sleep_for(std::chrono::microseconds(200));
                               }),
               InputError);
  EXPECT_LT(ran.load(), 2000);
}

TEST(ParallelChunks, CallingThreadErrorWaitsForTheWorkers) {
  const std::thread::id caller = std::this_thread::get_id();
  std::atomic<int> running{0};
  EXPECT_THROW(parallel_chunks(64, 1, 3,
                               [&](index_t, index_t, index_t) {
                                 ++running;
                                 std::this_thread::sleep_for(std::chrono::milliseconds(2));
                                 --running;
                                 if (std::this_thread::get_id() == caller) throw InputError("x");
                               }),
               InputError);
  EXPECT_EQ(running.load(), 0);  // every worker has returned before the rethrow
}

// Asks for 1024 threads under an address-space limit with room for a few dozen 8 MB thread
// stacks only; exits 3 when that ends in ResourceError naming the parameter threads.
[[noreturn]] void ask_for_more_threads_than_fit() {
  rlimit limit{};
  getrlimit(RLIMIT_AS, &limit);
  long pages = 0, resident = 0;
  if (FILE* f = std::fopen("/proc/self/statm", "r")) {
    if (std::fscanf(f, "%ld %ld", &pages, &resident) != 2) pages = 0;
    std::fclose(f);
  }
  limit.rlim_cur = static_cast<rlim_t>(pages) * sysconf(_SC_PAGESIZE) + (256u << 20);
  setrlimit(RLIMIT_AS, &limit);
  try {
    parallel_chunks(4096, 1, 1024, [](index_t, index_t, index_t) {
      std::this_thread::sleep_for(std::chrono::microseconds(100));
    });
    std::fprintf(stderr, "all 1024 threads started\n");
    std::_Exit(2);
  } catch (const ResourceError& e) {
    std::fprintf(stderr, "%s\n", e.what());
    std::_Exit(std::string(e.what()).find("parameter threads") != std::string::npos ? 3 : 4);
  }
}

// A thread that cannot be started gives ResourceError naming the parameter, after the threads
// already started have stopped. Before: std::system_error left joinable threads behind,
// std::terminate, SIGABRT.
TEST(ParallelChunksDeathTest, ThreadsTheSystemCannotStartAreAResourceError) {
#ifdef HEXMERGE_TEST_ASAN
  GTEST_SKIP() << "AddressSanitizer reserves more address space than the limit allows";
#else
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  EXPECT_EXIT(ask_for_more_threads_than_fit(), testing::ExitedWithCode(3),
              "could not start thread");
#endif
}

}  // namespace
}  // namespace hexmerge
