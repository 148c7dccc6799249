#pragma once
// How floesim reports failure — one way for each kind:
//  * bad input (files, keys, values, usage): throw InputError; the CLI exits 2.
//    The message names the file, the key or dataset, and what was expected.
//  * a run that fails numerically: throw RunError; the CLI exits 1.
//  * numerical kernels (solvers) do not throw on non-convergence: they return a
//    typed status that the caller inspects.
//  * internal invariants: FLOESIM_ASSERT, active in debug builds only.

#include <stdexcept>
#include <string>

namespace floesim {

class InputError : public std::runtime_error {
public:
  using std::runtime_error::runtime_error;
};

class RunError : public std::runtime_error {
public:
  using std::runtime_error::runtime_error;
};

// Builds "FILE:LINE: key 'KEY': MESSAGE" (parts left empty are omitted).
std::string where(const std::string& file, long line, const std::string& key,
                  const std::string& message);

}  // namespace floesim

#ifndef NDEBUG
#include <cassert>
#define FLOESIM_ASSERT(cond) assert(cond)
#else
#define FLOESIM_ASSERT(cond) ((void)0)
#endif
