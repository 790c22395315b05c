// f(begin, end) over blocks of `grain` indices of [0, n), in parallel (TBB), in an arena of
// `threads` threads (0: all). The transport products' one way of splitting rows or columns.
#pragma once

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <cstddef>

namespace sl {

template <typename F>
void forBlocks(size_t n, size_t grain, int threads, F&& f) {
    auto body = [&] {
        tbb::parallel_for(tbb::blocked_range<size_t>(0, n, grain),
                          [&](const tbb::blocked_range<size_t>& r) { f(r.begin(), r.end()); });
    };
    if (threads > 0) {
        tbb::task_arena arena(threads);
        arena.execute(body);
    } else {
        body();
    }
}

}  // namespace sl
