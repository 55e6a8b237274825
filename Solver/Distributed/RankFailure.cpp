#include "RankFailure.h"

#include "DeviceFault.h"
#include "Parameters.h"

#include <new>
#include <stdexcept>

namespace pbf::distributed
{

void throwRankFailure(FailureKind kind, const std::string& text)
{
  switch (kind)
  {
    case FailureKind::DeviceFault:
      throw DeviceFault(text, false);
    case FailureKind::InvalidInput:
      throw InvalidInput(text);
    case FailureKind::Other:
      break;
  }
  throw std::runtime_error(text);
}

void failTogether(Communicator& communicator, const std::exception_ptr& error)
{
  if (communicator.failed())
  {
    std::rethrow_exception(error);
  }
  const std::string who =
    "rank " + std::to_string(communicator.rank()) + " of " + std::to_string(communicator.size()) + ": ";
  try
  {
    std::rethrow_exception(error);
  }
  catch (const DeviceFault& fault)
  {
    const std::string text = who + fault.what();
    communicator.abandon(FailureKind::DeviceFault, text);
    throw DeviceFault(text, fault.contextLost());
  }
  catch (const InvalidInput& invalid)
  {
    const std::string text = who + invalid.what();
    communicator.abandon(FailureKind::InvalidInput, text);
    throw InvalidInput(text);
  }
  catch (const std::bad_alloc&)
  {
    const std::string text = who + "out of host memory (std::bad_alloc)";
    communicator.abandon(FailureKind::Other, text);
    throw std::runtime_error(text);
  }
  catch (const std::exception& other)
  {
    const std::string text = who + other.what();
    communicator.abandon(FailureKind::Other, text);
    throw std::runtime_error(text);
  }
  catch (...)
  {
    const std::string text = who + "an unknown exception";
    communicator.abandon(FailureKind::Other, text);
    throw std::runtime_error(text);
  }
}

} // namespace pbf::distributed
