// Failing together: a decomposed run stops on every rank with the same error when one rank fails.
//
// Without this, a rank whose GPU faults mid-step throws and leaves the step, and the others wait
// forever in the step's next exchange for its messages. The collective work of a rank (a step,
// the statistics, the health scan) runs inside together(): an exception of its own is announced
// to the other ranks (Communicator::abandon) and rethrown as "rank r of n: what", the type kept;
// the other ranks' communicators throw that same error from their next wait.
#pragma once

#include "Communicator.h"

#include <exception>
#include <string>
#include <utility>

namespace pbf::distributed
{

// Throws the error a notice describes: DeviceFault (context not lost: this rank's device is
// fine), InvalidInput or std::runtime_error, with the text.
[[noreturn]] void throwRankFailure(FailureKind kind, const std::string& text);

// In a catch block of a rank's collective work: if the communicator has already failed, the
// error is another rank's (or already announced) and is rethrown as it is; otherwise it is this
// rank's own: it is announced to every rank and thrown, prefixed with "rank r of n: ".
[[noreturn]] void failTogether(Communicator& communicator, const std::exception_ptr& error);

// Runs a rank's collective work; see failTogether.
template <class F>
decltype(auto) together(Communicator& communicator, F&& work)
{
  try
  {
    return std::forward<F>(work)();
  }
  catch (...)
  {
    failTogether(communicator, std::current_exception());
  }
}

} // namespace pbf::distributed
