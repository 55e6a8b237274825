// The exchanges of DeviceSubdomainStepper: the ghost refreshes around the interior passes
// (sendRefresh, receiveRefresh), in place from page-locked memory over MPI or copied through the
// Communicator's byte vectors, and the upload of received messages.
// Included at the end of DeviceSubdomainStepper.h; not a header of its own.
#pragma once

namespace pbf::cuda
{

template <class Real, class Device>
void DeviceSubdomainStepper<Real, Device>::uploadMessages(unsigned char* to,
  const std::vector<std::pair<int, std::size_t>>& from,
  std::size_t skip,
  bool aside)
{
  std::size_t total = 0;
  for (const auto& [rank, bytes] : from)
  {
    total += bytes;
    (void)rank;
  }
  if (total == 0)
  {
    return;
  }
  unsigned char* staging = hostBuffer(hostRecv_, total);
  std::size_t at = 0;
  for (const auto& [rank, bytes] : from)
  {
    const distributed::Bytes& message = in_[static_cast<std::size_t>(rank)];
    std::memcpy(staging + at, message.data() + skip, bytes);
    at += bytes;
  }
  if (aside)
  {
    device_->uploadAside(to, staging, total);
  }
  else
  {
    device_->upload(to, staging, total);
  }
}

template <class Real, class Device>
template <class T>
void DeviceSubdomainStepper<Real, Device>::sendRefresh(subdomain::RefreshFields<T> fields)
{
  const std::size_t record = fields.record();
  const std::size_t sendBytes = (sendLeft_ + sendRight_) * record;
  unsigned char* pack = packBuffer(sendBytes);
  unsigned char* staging = hostBuffer(hostPack_, sendBytes);
  auto edge = device_->borderExecutor(); // behind the border launch it packs
  subdomain::packFields(edge, sendList_, sendLeft_, sendRight_, fields, pack);
  // Off the compute queue: the interior pass queued next does not wait for this copy.
  device_->downloadAside(staging, pack, sendBytes);
}

template <class Real, class Device>
template <class T>
void DeviceSubdomainStepper<Real, Device>::receiveRefresh(subdomain::RefreshFields<T> fields)
{
  const std::size_t record = fields.record();
  const std::size_t sendBytes = (sendLeft_ + sendRight_) * record;
  const auto waitStart = Clock::now();
  device_->waitEvent();
  const auto start = Clock::now();
  exchange_.deviceWaitMilliseconds +=
    std::chrono::duration<double, std::milli>(start - waitStart).count();
  checkLists(); // their copy was queued before the border fields'
  const std::size_t leftBytes = ghostLeft_ * record, rightBytes = ghostRight_ * record;
  unsigned char* recv = recvBuffer(leftBytes + rightBytes);
  if (inPlace_)
  {
    // Straight from the page-locked border fields to the neighbours and from theirs into the
    // page-locked staging of the upload: no host copy (the last upload from that staging was
    // queued on the copy stream before the download just waited for, so it is done).
    unsigned char* staging = hostBuffer(hostRecv_, leftBytes + rightBytes);
    const auto exchangeStart = Clock::now();
    exchangeWithNeighborsInPlace(
      sendLeft_ * record, sendRight_ * record, staging, leftBytes, rightBytes);
    exchange_.refreshWaitMilliseconds += since(exchangeStart);
    if (leftBytes + rightBytes > 0)
    {
      // Off the compute queue too: it overlaps the interior pass; the scatter waits for it.
      device_->uploadAside(recv, staging, leftBytes + rightBytes);
    }
  }
  else
  {
    exchangeCopied(record, sendBytes, recv);
  }
  auto exec = device_->executor();
  subdomain::scatterFields(exec, ghostList_, ghostLeft_, ghostRight_, recv, fields);
  exchange_.ghostMilliseconds += since(start);
}

template <class Real, class Device>
void DeviceSubdomainStepper<Real, Device>::exchangeWithNeighborsInPlace(std::size_t sendLeftBytes,
  std::size_t sendRightBytes,
  unsigned char* receive,
  std::size_t leftBytes,
  std::size_t rightBytes)
{
  const int me = communicator_.rank();
  const int last = communicator_.size() - 1;
  std::fill(sendSizes_.begin(), sendSizes_.end(), std::size_t(0));
  std::fill(inSizes_.begin(), inSizes_.end(), std::size_t(0));
  std::fill(sendAt_.begin(), sendAt_.end(), nullptr);
  std::fill(receiveAt_.begin(), receiveAt_.end(), nullptr);
  if (me > 0)
  {
    const auto left = static_cast<std::size_t>(me - 1);
    sendAt_[left] = hostPack_.data;
    sendSizes_[left] = sendLeftBytes;
    receiveAt_[left] = receive;
    inSizes_[left] = leftBytes;
  }
  if (me < last)
  {
    const auto right = static_cast<std::size_t>(me + 1);
    sendAt_[right] = hostPack_.data + sendLeftBytes;
    sendSizes_[right] = sendRightBytes;
    receiveAt_[right] = receive + leftBytes;
    inSizes_[right] = rightBytes;
  }
  communicator_.exchangeKnownSizesInPlace(sendAt_, sendSizes_, receiveAt_, inSizes_);
}

template <class Real, class Device>
void DeviceSubdomainStepper<Real, Device>::exchangeCopied(std::size_t record,
  std::size_t sendBytes,
  unsigned char* recv)
{
  const int me = communicator_.rank();
  const int last = communicator_.size() - 1;
  const unsigned char* staging = hostPack_.data;
  for (auto& o : out_)
  {
    o.clear();
  }
  if (me > 0)
  {
    out_[static_cast<std::size_t>(me - 1)].assign(staging, staging + sendLeft_ * record);
  }
  if (me < last)
  {
    out_[static_cast<std::size_t>(me + 1)].assign(
      staging + sendLeft_ * record, staging + sendBytes);
  }
  // Both sides know the sizes: the ghost lists were agreed when the ghosts were sent.
  std::fill(inSizes_.begin(), inSizes_.end(), std::size_t(0));
  if (me > 0)
  {
    inSizes_[static_cast<std::size_t>(me - 1)] = ghostLeft_ * record;
  }
  if (me < last)
  {
    inSizes_[static_cast<std::size_t>(me + 1)] = ghostRight_ * record;
  }
  const auto exchangeStart = Clock::now();
  communicator_.exchangeKnownSizes(out_, in_, inSizes_);
  exchange_.refreshWaitMilliseconds += since(exchangeStart);
  messages_.clear();
  const auto expect = [&](int from, std::size_t bytes)
  {
    const distributed::Bytes& message = in_[static_cast<std::size_t>(from)];
    if (message.size() != bytes)
    {
      throw std::logic_error("ghost refresh from rank " + std::to_string(from) + ": " +
        std::to_string(message.size()) + " bytes, expected " + std::to_string(bytes));
    }
    messages_.emplace_back(from, bytes);
  };
  if (me > 0)
  {
    expect(me - 1, ghostLeft_ * record);
  }
  if (me < last)
  {
    expect(me + 1, ghostRight_ * record);
  }
  // Off the compute queue too: it overlaps the interior pass; the scatter waits for it.
  uploadMessages(recv, messages_, 0, true);
}

} // namespace pbf::cuda
