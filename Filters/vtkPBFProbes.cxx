#include "vtkPBFProbes.h"

#include "vtkDataSet.h"
#include "vtkDoubleArray.h"
#include "vtkFloatArray.h"
#include "vtkIdTypeArray.h"
#include "vtkIntArray.h"
#include "vtkPointData.h"
#include "vtkPoints.h"
#include "vtkPolyData.h"

#include "Probes.h"

#include <limits>
#include <memory>
#include <sstream>

namespace
{

// The frame's particles (port 0's output, float or double alike) as the solver's sums over them.
template <class Array>
std::unique_ptr<pbf::ParticleSums> SumsOfArrays(
  vtkPolyData* particles, const pbf::Parameters& parameters)
{
  using Real = typename Array::ValueType;
  const vtkIdType n = particles->GetNumberOfPoints();
  auto* x = Array::SafeDownCast(particles->GetPoints()->GetData());
  auto* v = Array::SafeDownCast(particles->GetPointData()->GetArray("velocity"));
  auto* p = Array::SafeDownCast(particles->GetPointData()->GetArray("pressure"));
  if (!x || !v || !p)
  {
    return nullptr;
  }
  return std::make_unique<pbf::ParticleSums>(parameters,
    reinterpret_cast<const pbf::Vec3<Real>*>(x->GetPointer(0)),
    reinterpret_cast<const pbf::Vec3<Real>*>(v->GetPointer(0)), p->GetPointer(0),
    static_cast<std::size_t>(n));
}

// The frame's particles (port 0's output) as the solver's sums over them; null without particles.
std::unique_ptr<pbf::ParticleSums> SumsOf(vtkPolyData* particles, const pbf::Parameters& parameters)
{
  if (!particles || !particles->GetPoints() || particles->GetNumberOfPoints() == 0)
  {
    return nullptr;
  }
  std::unique_ptr<pbf::ParticleSums> sums = SumsOfArrays<vtkFloatArray>(particles, parameters);
  return sums ? std::move(sums) : SumsOfArrays<vtkDoubleArray>(particles, parameters);
}

// kProbeSums values per point over this rank's particles, added over the ranks.
std::vector<double> SumsAt(vtkPolyData* particles, const pbf::Parameters& parameters,
  const std::vector<pbf::Vec3d>& points, pbf::distributed::Communicator* ranks)
{
  std::vector<double> sums;
  const std::unique_ptr<pbf::ParticleSums> mine = SumsOf(particles, parameters);
  if (mine)
  {
    mine->at(points, sums);
  }
  else
  {
    sums.assign(points.size() * pbf::kProbeSums, 0.0);
  }
  return ranks ? pbf::distributed::sumInRankOrder(*ranks, sums) : sums;
}

std::vector<pbf::Vec3d> PointsOf(vtkDataSet* data)
{
  std::vector<pbf::Vec3d> points;
  const vtkIdType n = data ? data->GetNumberOfPoints() : 0;
  for (vtkIdType i = 0; i < n; ++i)
  {
    double q[3];
    data->GetPoint(i, q);
    points.push_back(pbf::Vec3d{ q[0], q[1], q[2] });
  }
  return points;
}

vtkSmartPointer<vtkDoubleArray> Column(const char* name, int components, vtkIdType rows)
{
  auto column = vtkSmartPointer<vtkDoubleArray>::New();
  column->SetName(name);
  column->SetNumberOfComponents(components);
  column->SetNumberOfTuples(rows);
  return column;
}

} // namespace

//------------------------------------------------------------------------------
vtkSmartPointer<vtkTable> vtkPBFProbeTable(vtkDataSet* probes, vtkPolyData* particles,
  const pbf::Parameters& parameters, pbf::distributed::Communicator* ranks,
  std::vector<vtkIdType>& outside)
{
  const std::vector<pbf::Vec3d> at = PointsOf(probes);
  // Each probe, then its gauge column: every rank lays the points out alike.
  std::vector<pbf::Vec3d> points;
  std::vector<std::size_t> first, samples;
  for (const pbf::Vec3d& q : at)
  {
    first.push_back(points.size());
    points.push_back(q);
    const std::vector<pbf::Vec3d> column = pbf::gaugeColumn(parameters, q);
    samples.push_back(column.size());
    points.insert(points.end(), column.begin(), column.end());
  }
  const std::vector<double> sums = SumsAt(particles, parameters, points, ranks);

  const auto rows = static_cast<vtkIdType>(at.size());
  vtkNew<vtkIdTypeArray> index;
  index->SetName("Probe");
  index->SetNumberOfTuples(rows);
  auto position = Column("Position", 3, rows);
  auto velocity = Column("velocity", 3, rows);
  auto pressure = Column("pressure", 1, rows);
  auto height = Column("WaterHeight", 1, rows);
  auto fraction = Column("FluidFraction", 1, rows);
  outside.clear();
  for (vtkIdType k = 0; k < rows; ++k)
  {
    const std::size_t s = static_cast<std::size_t>(k);
    const double* probe = sums.data() + first[s] * pbf::kProbeSums;
    const pbf::ProbeReading r = pbf::readProbe(
      parameters, at[s], probe, probe + pbf::kProbeSums, samples[s]);
    if (!r.inside)
    {
      outside.push_back(k);
    }
    index->SetValue(k, k);
    position->SetTuple3(k, at[s].x, at[s].y, at[s].z);
    velocity->SetTuple3(k, r.velocity.x, r.velocity.y, r.velocity.z);
    pressure->SetValue(k, r.pressure);
    height->SetValue(k, r.waterHeight);
    fraction->SetValue(k, r.fraction);
  }
  auto table = vtkSmartPointer<vtkTable>::New();
  table->AddColumn(index);
  table->AddColumn(position);
  table->AddColumn(velocity);
  table->AddColumn(pressure);
  table->AddColumn(height);
  table->AddColumn(fraction);
  return table;
}

//------------------------------------------------------------------------------
void vtkPBFAddSurfacePressure(vtkPolyData* surfaces, vtkPolyData* particles,
  const pbf::Parameters& parameters, const pbf::SurfaceSolids& solids,
  pbf::distributed::Communicator* ranks)
{
  const std::vector<pbf::Vec3d> points = PointsOf(surfaces);
  std::vector<int> solidOf(points.size(), -1);
  if (auto* index = vtkIntArray::SafeDownCast(surfaces->GetPointData()->GetArray("Solid")))
  {
    for (std::size_t k = 0; k < points.size(); ++k)
    {
      solidOf[k] = index->GetValue(static_cast<vtkIdType>(k));
    }
  }
  std::vector<double> sums;
  const std::unique_ptr<pbf::ParticleSums> mine = SumsOf(particles, parameters);
  if (mine)
  {
    mine->onSolids(solids, points, solidOf, sums);
  }
  else
  {
    sums.assign(points.size(), 0.0);
  }
  if (ranks)
  {
    sums = pbf::distributed::sumInRankOrder(*ranks, sums);
  }
  auto pressure = Column("pressure", 1, static_cast<vtkIdType>(points.size()));
  for (std::size_t k = 0; k < points.size(); ++k)
  {
    pressure->SetValue(static_cast<vtkIdType>(k), sums[k]);
  }
  surfaces->GetPointData()->AddArray(pressure);
}

//------------------------------------------------------------------------------
std::string vtkPBFDescribeProbes(vtkDataSet* probes, const std::vector<vtkIdType>& outside)
{
  std::ostringstream text;
  const std::size_t shown = std::min<std::size_t>(outside.size(), 3);
  for (std::size_t k = 0; k < shown; ++k)
  {
    double q[3];
    probes->GetPoint(outside[k], q);
    text << (k > 0 ? ", " : "") << "probe " << outside[k] << " at (" << q[0] << ", " << q[1]
         << ", " << q[2] << ")";
  }
  if (outside.size() > shown)
  {
    text << " and " << outside.size() - shown << " more";
  }
  return text.str();
}
