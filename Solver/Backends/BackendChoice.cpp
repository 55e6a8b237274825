#include "BackendChoice.h"

#include "Communicator.h"

#include <stdexcept>
#include <vector>

namespace pbf
{

BackendChoice chooseBackend(BackendRequest requested, bool cudaHere, const std::string& whyNot,
  distributed::Communicator* ranks)
{
  bool cuda = cudaHere;
  std::string noCuda = whyNot;
  if (ranks && (requested == BackendRequest::CUDA || requested == BackendRequest::Auto))
  {
    bool everyRank = true;
    for (const std::vector<double>& theirs : distributed::allGather(*ranks, { cuda ? 1.0 : 0.0 }))
    {
      everyRank = everyRank && theirs[0] != 0.0;
    }
    if (cuda && !everyRank)
    {
      noCuda = "another rank of the " + std::to_string(ranks->size()) + " has no usable GPU";
    }
    else if (!cuda)
    {
      noCuda = "rank " + std::to_string(ranks->rank()) + ": " + noCuda;
    }
    cuda = everyRank;
  }
  BackendChoice choice;
  switch (requested)
  {
    case BackendRequest::CUDA:
      if (!cuda)
      {
        throw std::runtime_error("Backend = CUDA: CUDA backend unavailable: " + noCuda +
          " (choose Auto or CPU (OpenMP))");
      }
      choice.backend = Backend::CUDA;
      break;
    case BackendRequest::OpenMP:
      choice.backend = Backend::OpenMP;
      break;
    case BackendRequest::Serial:
      choice.backend = Backend::Serial;
      break;
    case BackendRequest::Auto:
      choice.backend = cuda ? Backend::CUDA : Backend::OpenMP;
      choice.noCuda = cuda ? std::string() : noCuda;
      break;
  }
  return choice;
}

} // namespace pbf
