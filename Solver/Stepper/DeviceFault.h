// A failure of the device a backend runs on, as opposed to bad input (InvalidInput).
#pragma once

#include <stdexcept>
#include <string>

namespace pbf
{

// A CUDA error during a run: the device was lost, a kernel faulted or trapped, a launch failed.
// The backend's state on the device is gone, so the caller must resume from a copy on the host
// (a checkpoint) or stop. contextLost() is true when the error is sticky: CUDA then refuses every
// later call of this process, so the GPU stays unusable until the application restarts and
// cudaAvailable() says so from then on.
class DeviceFault : public std::runtime_error
{
public:
  DeviceFault(const std::string& what, bool contextLost)
    : std::runtime_error(what)
    , contextLost_(contextLost)
  {
  }
  bool contextLost() const { return contextLost_; }

private:
  bool contextLost_;
};

} // namespace pbf
