#include "hexmerge/core/work_queue.h"

#include <gtest/gtest.h>

#include <vector>

namespace hexmerge {
namespace {

std::vector<index_t> drain(WorkQueue& work) {
  std::vector<index_t> out;
  while (!work.empty()) out.push_back(work.pop());
  return out;
}

TEST(WorkQueue, PopsInTheOrderFirstPushed) {
  WorkQueue work(10);
  EXPECT_TRUE(work.empty());
  for (index_t i : {7u, 2u, 9u, 0u}) work.push(i);
  EXPECT_FALSE(work.empty());
  EXPECT_EQ(drain(work), (std::vector<index_t>{7, 2, 9, 0}));
}

TEST(WorkQueue, HoldsAnIdOnceWhileItWaits) {
  WorkQueue work(5);
  work.push(3);
  work.push(1);
  work.push(3);  // already waiting: stays where it was first pushed
  work.push(1);
  EXPECT_EQ(drain(work), (std::vector<index_t>{3, 1}));
}

TEST(WorkQueue, TakesAnIdAgainOncePopped) {
  WorkQueue work(3);
  work.push(2);
  work.push(0);
  EXPECT_EQ(work.pop(), 2u);
  work.push(2);  // popped: goes to the back
  work.push(0);  // still waiting
  EXPECT_EQ(drain(work), (std::vector<index_t>{0, 2}));
}

}  // namespace
}  // namespace hexmerge
