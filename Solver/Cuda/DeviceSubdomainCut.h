// The cut and the migration plan of DeviceSubdomainStepper (its step 1 and 2): the column
// histograms and the balanced slabs, the owners of the particles, the movers packed, exchanged with
// the ranks that send or receive, and unpacked behind the kept ones.
// Included at the end of DeviceSubdomainStepper.h; not a header of its own (it does
// not include it: the class whose members it defines comes from there).
#pragma once

namespace pbf::cuda
{

template <class Real, class Device>
void DeviceSubdomainStepper<Real, Device>::uploadSlabs()
{
  for (std::size_t r = 0; r < slabs_.first.size(); ++r)
  {
    hostFirst_[r] = slabs_.first[r];
  }
  device_->upload(slabFirst_, hostFirst_.data(), hostFirst_.size() * sizeof(int));
}

template <class Real, class Device>
void DeviceSubdomainStepper<Real, Device>::cut(int from, int predicted)
{
  const auto start = Clock::now();
  const auto nx = static_cast<std::size_t>(columns_.nx);
  const std::size_t histograms = predicted >= 0 ? 2 : 1;
  auto exec = device_->executor();
  const std::size_t copies = nx * subdomain::kCounterCopies; // one histogram's counters
  exec.fillZero(columnCounts_, histograms * copies * sizeof(std::uint32_t));
  subdomain::countColumns(exec, columns_, count(n_), vec_[from], columnCounts_);
  if (predicted >= 0)
  {
    subdomain::countColumns(exec, columns_, count(n_), vec_[predicted], columnCounts_ + copies);
  }
  device_->download(hostCounts_.data(), columnCounts_, histograms * copies * sizeof(std::uint32_t));
  device_->synchronize();
  std::vector<double>& mine = columnsMine_;
  mine.resize(2 * nx);
  predictedMine_.resize(nx);
  for (std::size_t c = 0; c < nx; ++c)
  {
    mine[c] = static_cast<double>(subdomain::sumOfCopies(hostCounts_.data(), c));
    predictedMine_[c] = subdomain::sumOfCopies(hostCounts_.data(), (histograms - 1) * nx + c);
    mine[nx + c] = static_cast<double>(predictedMine_[c]);
  }
  std::vector<std::uint64_t>& perColumn = columnsAll_;
  perColumn.assign(nx, 0);
  predictedAll_.assign(nx, 0);
  const std::vector<std::vector<double>> all = distributed::allGather(communicator_, mine);
  for (const std::vector<double>& r : all)
  {
    if (r.size() != 2 * nx)
    {
      throw std::logic_error("decomposed CUDA step: a rank's column counts have the wrong length");
    }
    for (std::size_t c = 0; c < nx; ++c)
    {
      perColumn[c] += static_cast<std::uint64_t>(r[c]);
      predictedAll_[c] += static_cast<std::uint64_t>(r[nx + c]);
    }
  }
  const distributed::Slabs balanced = distributed::Slabs::balanced(perColumn, communicator_.size());
  exchange_.cutMoved = balanced.first != slabs_.first;
  slabs_ = balanced;
  uploadSlabs();
  setWindow();
  // How many particles each rank sends this one in the migration: its predicted positions in
  // this rank's columns (every rank's own counts came with the allGather).
  const int me = communicator_.rank();
  arrivingFrom_.assign(all.size(), 0);
  for (std::size_t c = 0; c < nx; ++c)
  {
    if (ownerOf(static_cast<int>(c)) != me)
    {
      continue;
    }
    for (std::size_t from = 0; from < all.size(); ++from)
    {
      if (static_cast<int>(from) != me)
      {
        arrivingFrom_[from] += static_cast<std::uint64_t>(all[from][nx + c]);
      }
    }
  }
  exchange_.migrationMilliseconds += since(start);
}

template <class Real, class Device>
void DeviceSubdomainStepper<Real, Device>::checkOwnerCounts(const std::uint32_t* expected)
{
  const auto ranks = static_cast<std::size_t>(communicator_.size());
  for (std::size_t i = 0; i < ranks + 1; ++i)
  {
    failUnlessExpected(
      subdomain::sumOfCopies(setupCounts_, i), expected[i], i, "leavers to rank key");
  }
}

template <class Real, class Device>
void DeviceSubdomainStepper<Real, Device>::exchangeMigrants(
  const unsigned char* staging, const std::uint32_t* owners)
{
  using Record = subdomain::Migrant<Real>;
  const int me = communicator_.rank();
  const auto ranks = static_cast<std::size_t>(communicator_.size());
  std::size_t offset = 0;
  for (std::size_t to = 0; to < ranks; ++to)
  {
    out_[to].clear();
    if (static_cast<int>(to) == me)
    {
      continue;
    }
    const std::size_t bytes = std::size_t(owners[to + 1]) * sizeof(Record);
    out_[to].assign(staging + offset, staging + offset + bytes);
    offset += bytes;
  }
  // Every rank knows what each sends it (the cut's counts): point-to-point with the ranks
  // that send or receive, no collective over all ranks.
  for (std::size_t from = 0; from < ranks; ++from)
  {
    inSizes_[from] = std::size_t(arrivingFrom_[from]) * sizeof(Record);
  }
  communicator_.exchangeKnownSizes(out_, in_, inSizes_);
  for (std::size_t from = 0; from < ranks; ++from)
  {
    if (in_[from].size() != std::size_t(arrivingFrom_[from]) * sizeof(Record))
    {
      throw std::logic_error("migration from rank " + std::to_string(from) + ": " +
        std::to_string(in_[from].size()) + " bytes, expected " +
        std::to_string(std::size_t(arrivingFrom_[from]) * sizeof(Record)));
    }
  }
}

template <class Real, class Device>
typename DeviceSubdomainStepper<Real, Device>::Roles4 DeviceSubdomainStepper<Real, Device>::migrate(
  Roles4 r)
{
  const auto start = Clock::now();
  const int me = communicator_.rank();
  const auto ranks = static_cast<std::size_t>(communicator_.size());
  const std::uint32_t n = count(n_);
  auto exec = device_->executor();
  exec.fillZero(ownerCounts_, (ranks + 1) * subdomain::kCounterCopies * sizeof(std::uint32_t));
  auto* order = reinterpret_cast<std::uint32_t*>(lambda_); // unused identity
  subdomain::ownerKeys(
    exec, columns_, slabView(), n, vec_[r.p], keys_[0], order, ownerCounts_);
  // The counts per destination from this rank's predicted column counts (the cut's); the
  // device's own come back without a wait and are checked at the wait below.
  std::vector<std::uint32_t>& owners = ownerExpected_;
  std::fill(owners.begin(), owners.end(), 0u);
  for (std::size_t c = 0; c < predictedMine_.size(); ++c)
  {
    const int o = ownerOf(static_cast<int>(c));
    owners[o == me ? 0 : static_cast<std::size_t>(o) + 1] += predictedMine_[c];
  }
  device_->download(
    setupCounts_, ownerCounts_, (ranks + 1) * subdomain::kCounterCopies * sizeof(std::uint32_t));
  if (owners[0] > n)
  {
    throw std::logic_error("decomposed CUDA step: more particles stay than there are");
  }
  const std::uint32_t stay = owners[0];
  const std::uint32_t leaving = n - stay;
  using Record = subdomain::Migrant<Real>;
  auto* packed = reinterpret_cast<Record*>(packBuffer(std::size_t(leaving) * sizeof(Record)));
  unsigned char* staging = hostBuffer(hostPack_, std::size_t(leaving) * sizeof(Record));
  if (leaving > 0)
  {
    // ownedList_ and sendList_/ghostList_ are free until the cell sort.
    std::uint32_t offset = 0;
    for (std::size_t to = 0; to < ranks; ++to)
    {
      const std::uint32_t c = owners[to + 1];
      if (c > 0)
      {
        subdomain::selectKey<Real>(
          exec, n, keys_[0], static_cast<CellKey>(to + 1), ownedList_ + offset, selected_ + 2);
        offset += c;
      }
    }
    subdomain::packMigrants(
      exec, leaving, ownedList_, vec_[r.x], vec_[r.p], vec_[r.v], pressure_, id_, liquid_, packed);
    device_->download(staging, packed, std::size_t(leaving) * sizeof(Record));
  }
  // The exchange needs the leavers' bytes (and the counts) only: the holes are filled while
  // the host exchanges them.
  device_->recordEvent();
  if (leaving > 0)
  {
    reserveBorderLists(leaving); // holes and movers: at most the leavers each
    subdomain::selectHolesAndMovers<Real>(
      exec, n, stay, keys_[0], sendList_, ghostList_, selected_);
    const std::uint32_t most = std::min(stay, leaving);
    subdomain::fillHoles<Real>(exec, most, selected_, sendList_, ghostList_, vec_[r.x]);
    subdomain::fillHoles<Real>(exec, most, selected_, sendList_, ghostList_, vec_[r.p]);
    subdomain::fillHoles<Real>(exec, most, selected_, sendList_, ghostList_, vec_[r.v]);
    subdomain::fillHoles<Real>(exec, most, selected_, sendList_, ghostList_, pressure_);
    subdomain::fillHoles<Real>(exec, most, selected_, sendList_, ghostList_, id_);
    if (liquid_)
    {
      subdomain::fillHoles<Real>(exec, most, selected_, sendList_, ghostList_, liquid_);
    }
  }
  device_->waitEvent();
  checkOwnerCounts(owners.data());
  exchangeMigrants(staging, owners.data());
  std::size_t arrivingBytes = 0;
  std::vector<std::pair<int, std::size_t>>& from = messages_;
  from.clear();
  for (std::size_t r = 0; r < in_.size(); ++r)
  {
    arrivingBytes += in_[r].size();
    from.emplace_back(static_cast<int>(r), in_[r].size());
  }
  const std::size_t arriving = arrivingBytes / sizeof(Record);
  reserve(stay + arriving, stay);
  unsigned char* recv = recvBuffer(arrivingBytes);
  uploadMessages(recv, from);
  exec = device_->executor();
  subdomain::unpackMigrants(exec,
    stay,
    count(arriving),
    reinterpret_cast<const Record*>(recv),
    vec_[r.x],
    vec_[r.p],
    vec_[r.v],
    pressure_,
    id_,
    liquid_);
  n_ = stay + arriving;
  exchange_.migrated += arriving;
  exchange_.migrationMilliseconds += since(start);
  return r;
}

} // namespace pbf::cuda
