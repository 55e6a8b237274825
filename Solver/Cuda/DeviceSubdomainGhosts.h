// The ghost lists of DeviceSubdomainStepper (its steps 3 and 4): the border particles seeded to the
// neighbours, theirs appended, the cell sort of owned and ghosts, and the send and ghost lists
// selected from the sorted keys.
// Included at the end of DeviceSubdomainStepper.h; not a header of its own.
#pragma once

namespace pbf::cuda
{

template <class Real, class Device>
void DeviceSubdomainStepper<Real, Device>::checkGhostCounts(const std::uint32_t* expected)
{
  const auto at = (static_cast<std::size_t>(communicator_.size()) + 1) * subdomain::kCounterCopies;
  for (std::size_t i = 0; i < 2; ++i)
  {
    failUnlessExpected(setupCounts_[at + i], expected[i], i, "ghosts sent to side");
  }
}

template <class Real, class Device>
template <class Seed>
typename DeviceSubdomainStepper<Real, Device>::Roles4
DeviceSubdomainStepper<Real, Device>::receiveGhostsAs(Roles4 r)
{
  const auto start = Clock::now();
  const int me = communicator_.rank();
  const int last = communicator_.size() - 1;
  const std::uint32_t n = count(n_);
  auto exec = device_->executor();
  const GridGeometry<Real>& g = columns_;
  // No column is -1 or nx: a side without a neighbour selects nothing.
  const int leftColumn = me > 0 ? slabs_.first[static_cast<std::size_t>(me)] : -1;
  const int rightColumn = me < last ? slabs_.first[static_cast<std::size_t>(me) + 1] - 1 : -1;
  // Every message's length from the global predicted column counts (the cut's): no wait for
  // the device's counts, which come back with the seeds and are checked then.
  const std::size_t ranks = static_cast<std::size_t>(communicator_.size());
  sendLeft_ = ghostsSentLeft(me);
  sendRight_ = ghostsSentRight(me);
  ghostLeft_ = me > 0 ? ghostsSentRight(me - 1) : 0u;
  ghostRight_ = me < last ? ghostsSentLeft(me + 1) : 0u;
  // Room for this step's border lists: the columns sent, the ghosts, the border (sortByCell).
  reserveBorderLists(std::max(sendLeft_ + sendRight_, ghostLeft_ + ghostRight_));
  exec = device_->executor();
  subdomain::selectColumn(exec, g, n, vec_[r.p], leftColumn, sendList_, selected_);
  subdomain::selectColumn(exec, g, n, vec_[r.p], rightColumn, ghostList_, selected_ + 1);
  const std::uint32_t sent[2] = { sendLeft_, sendRight_ };
  device_->download(
    setupCounts_ + (ranks + 1) * subdomain::kCounterCopies, selected_, 2 * sizeof(std::uint32_t));
  if (sendLeft_ > n || sendRight_ > n) // one column may go both ways (a slab one column wide)
  {
    throw std::logic_error("decomposed CUDA step: more ghosts to send than particles");
  }
  auto* packed = reinterpret_cast<Seed*>(packBuffer((sendLeft_ + sendRight_) * sizeof(Seed)));
  subdomain::packSeeds<Real>(exec, sendLeft_, sendList_, vec_[r.p], liquid_, packed);
  subdomain::packSeeds<Real>(exec, sendRight_, ghostList_, vec_[r.p], liquid_, packed + sendLeft_);
  const std::size_t sendBytes = (sendLeft_ + sendRight_) * sizeof(Seed);
  unsigned char* staging = hostBuffer(hostPack_, sendBytes);
  if (sendBytes > 0)
  {
    device_->download(staging, packed, sendBytes);
  }
  device_->synchronize();
  checkGhostCounts(sent);
  const std::uint32_t ghosts = ghostLeft_ + ghostRight_;
  reserve(std::size_t(n) + ghosts, n);
  unsigned char* recv = recvBuffer(ghosts * sizeof(Seed));
  if (inPlace_)
  {
    // From the page-locked seeds to the neighbours and from theirs into the page-locked
    // staging of the upload, no host copy (~1 ms of a 32M step on 4 GPUs went to copying the
    // seeds through byte vectors, the device idle). The synchronize above finished the last
    // upload from that staging (the migration's).
    unsigned char* landing = hostBuffer(hostRecv_, ghosts * sizeof(Seed));
    exchangeWithNeighborsInPlace(sendLeft_ * sizeof(Seed),
      sendRight_ * sizeof(Seed),
      landing,
      ghostLeft_ * sizeof(Seed),
      ghostRight_ * sizeof(Seed));
    if (ghosts > 0)
    {
      device_->upload(recv, landing, ghosts * sizeof(Seed));
    }
  }
  else
  {
    exchangeSeedsCopied(staging, sizeof(Seed));
    uploadMessages(recv, messages_);
  }
  exec = device_->executor();
  subdomain::unpackSeeds<Real>(exec, n, ghosts, reinterpret_cast<const Seed*>(recv), vec_[r.x],
    vec_[r.p], vec_[r.v], id_, liquid_);
  total_ = std::size_t(n) + ghosts;
  exchange_.ghosts = ghosts;
  exchange_.ghostMilliseconds += since(start);
  return r;
}

template <class Real, class Device>
void DeviceSubdomainStepper<Real, Device>::exchangeSeedsCopied(
  const unsigned char* staging, std::size_t seed)
{
  const int me = communicator_.rank();
  const int last = communicator_.size() - 1;
  const std::size_t sendBytes = (sendLeft_ + sendRight_) * seed;
  for (auto& b : out_)
  {
    b.clear();
  }
  if (me > 0)
  {
    out_[static_cast<std::size_t>(me - 1)].assign(staging, staging + sendLeft_ * seed);
  }
  if (me < last)
  {
    out_[static_cast<std::size_t>(me + 1)].assign(
      staging + sendLeft_ * seed, staging + sendBytes);
  }
  // Both sides know the lengths: with the neighbours only, no collective over all ranks.
  std::fill(inSizes_.begin(), inSizes_.end(), std::size_t(0));
  if (me > 0)
  {
    inSizes_[static_cast<std::size_t>(me - 1)] = ghostLeft_ * seed;
  }
  if (me < last)
  {
    inSizes_[static_cast<std::size_t>(me + 1)] = ghostRight_ * seed;
  }
  communicator_.exchangeKnownSizes(out_, in_, inSizes_);
  for (std::size_t from = 0; from < in_.size(); ++from)
  {
    const bool left = static_cast<int>(from) == me - 1;
    const bool right = static_cast<int>(from) == me + 1;
    const std::size_t expected = (left ? ghostLeft_ : right ? ghostRight_ : 0u) * seed;
    if (in_[from].size() != expected)
    {
      throw std::logic_error("ghosts from rank " + std::to_string(from) + ": " +
        std::to_string(in_[from].size()) + " bytes, expected " + std::to_string(expected));
    }
  }
  messages_.clear();
  if (me > 0)
  {
    messages_.emplace_back(me - 1, ghostLeft_ * seed);
  }
  if (me < last)
  {
    messages_.emplace_back(me + 1, ghostRight_ * seed);
  }
}

template <class Real, class Device>
const CellKey* DeviceSubdomainStepper<Real, Device>::sortByCell(Roles4& r)
{
  const std::uint32_t total = count(total_);
  auto exec = device_->executor();
  const StepBuffers<Real> b = buffers();
  subdomain::cellKeys(exec,
    constants_.geometry,
    total,
    vec_[r.p],
    keys_[0],
    reinterpret_cast<std::uint32_t*>(lambda_));
  // On entry A = x, B = v, C = p, D free; on exit D = x, A = p, C = v, B free.
  const CellKey* keys = detail::sortAndGather(
    exec, b, constants_, total, vec_[r.x], vec_[r.v], vec_[r.p], vec_[r.free]);
  r = Roles4{ r.free, r.x, r.p, r.v };

  const int me = communicator_.rank();
  const int last = communicator_.size() - 1;
  // The keys are the window's: its columns from its first on.
  const int nx = constants_.geometry.nx;
  const int lo = constants_.geometry.firstColumn;
  const int begin = slabs_.first[static_cast<std::size_t>(me)] - lo;
  const int end = slabs_.first[static_cast<std::size_t>(me) + 1] - lo;
  // Empty ranges where there is no neighbour.
  const int sendL0 = me > 0 ? begin : 0, sendL1 = me > 0 ? begin + 1 : 0;
  const int sendR0 = me < last ? end - 1 : 0, sendR1 = me < last ? end : 0;
  const int ghostL0 = me > 0 ? begin - 1 : 0, ghostL1 = me > 0 ? begin : 0;
  const int ghostR0 = me < last ? end : 0, ghostR1 = me < last ? end + 1 : 0;
  subdomain::selectColumns<Real>(exec, nx, total, keys, sendL0, sendL1, sendList_, selected_);
  subdomain::selectColumns<Real>(
    exec, nx, total, keys, sendR0, sendR1, sendList_ + sendLeft_, selected_ + 1);
  subdomain::selectColumns<Real>(
    exec, nx, total, keys, ghostL0, ghostL1, ghostList_, selected_ + 2);
  subdomain::selectColumns<Real>(
    exec, nx, total, keys, ghostR0, ghostR1, ghostList_ + ghostLeft_, selected_ + 3);
  subdomain::selectColumns<Real>(exec, nx, total, keys, begin, end, ownedList_, selected_ + 4);
  subdomain::selectBorder<Real>(
    exec, nx, total, keys, begin, end, me > 0, me < last, true, borderList_, selected_ + 5);
  subdomain::selectBorder<Real>(
    exec, nx, total, keys, begin, end, me > 0, me < last, false, interiorList_, selected_ + 6);
  // The lengths are known already: the border is this slab's first column (with a left
  // neighbour) and its last (with a right one), the ones sent as ghosts, counted once where
  // they are the same column. The device's counts come back to page-locked memory without a
  // wait and are checked at the next one (checkLists): a protocol slip still fails the step,
  // instead of giving a wrong answer, without draining the device here.
  border_ = me > 0 && me < last && begin + 1 == end ? sendLeft_ : sendLeft_ + sendRight_;
  device_->download(listCounts_, selected_, 7 * sizeof(std::uint32_t));
  listsUnchecked_ = true;
  return keys;
}

template <class Real, class Device>
void DeviceSubdomainStepper<Real, Device>::checkLists()
{
  if (!listsUnchecked_)
  {
    return;
  }
  listsUnchecked_ = false;
  const std::uint32_t expected[7] = {
    sendLeft_, sendRight_, ghostLeft_, ghostRight_, count(n_), border_, count(n_) - border_
  };
  for (int i = 0; i < 7; ++i)
  {
    if (listCounts_[i] != expected[i])
    {
      throw std::logic_error("decomposed CUDA step: list " + std::to_string(i) + " has " +
        std::to_string(listCounts_[i]) + " particles, expected " + std::to_string(expected[i]));
    }
  }
}

} // namespace pbf::cuda
