// SPDX-License-Identifier: Apache-2.0
// Counts heap allocations of the test binary (operator new is replaced in
// allocation_counter.cpp) so tests can show a code path allocates nothing.
#pragma once

namespace weedspray::test {
long allocation_count();
}  // namespace weedspray::test
