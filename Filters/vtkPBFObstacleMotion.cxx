#include "vtkPBFObstacleMotion.h"

#include "vtkDataSet.h"
#include "vtkLandmarkTransform.h"
#include "vtkMatrix4x4.h"
#include "vtkNew.h"
#include "vtkPoints.h"

#include <cmath>
#include <sstream>

namespace
{

bool SamePose(const pbf::SolidPose& a, const pbf::SolidPose& b)
{
  return a.moving == b.moving && a.rotation == b.rotation && a.translation.x == b.translation.x &&
    a.translation.y == b.translation.y && a.translation.z == b.translation.z;
}

// The rigid motion that carries `reference` onto `now` (the same points in the same order):
// false when the points differ in number or the best rigid fit misses one by more than a
// millionth of the reference's size (the single-precision rounding of a transformed point).
bool FitRigidMotion(vtkDataSet* reference, vtkDataSet* now, pbf::SolidPose& pose)
{
  const vtkIdType n = reference->GetNumberOfPoints();
  if (now->GetNumberOfPoints() != n || now->GetNumberOfCells() != reference->GetNumberOfCells())
  {
    return false;
  }
  // At rest (every request of a still obstacle): the identity, the solid's bits as sampled,
  // found without copying a point.
  pose = pbf::SolidPose{};
  bool same = true;
  for (vtkIdType i = 0; i < n && same; ++i)
  {
    double a[3], b[3];
    reference->GetPoint(i, a);
    now->GetPoint(i, b);
    same = a[0] == b[0] && a[1] == b[1] && a[2] == b[2];
  }
  if (same)
  {
    return true;
  }
  vtkNew<vtkPoints> from, to;
  from->SetDataTypeToDouble();
  to->SetDataTypeToDouble();
  from->SetNumberOfPoints(n);
  to->SetNumberOfPoints(n);
  for (vtkIdType i = 0; i < n; ++i)
  {
    double a[3], b[3];
    reference->GetPoint(i, a);
    now->GetPoint(i, b);
    from->SetPoint(i, a);
    to->SetPoint(i, b);
  }
  vtkNew<vtkLandmarkTransform> fit;
  fit->SetModeToRigidBody();
  fit->SetSourceLandmarks(from);
  fit->SetTargetLandmarks(to);
  fit->Update();
  vtkMatrix4x4* m = fit->GetMatrix();
  pose.moving = true;
  for (int r = 0; r < 3; ++r)
  {
    for (int c = 0; c < 3; ++c)
    {
      pose.rotation[static_cast<std::size_t>(3 * r + c)] = m->GetElement(r, c);
    }
  }
  pose.translation = { m->GetElement(0, 3), m->GetElement(1, 3), m->GetElement(2, 3) };
  double bounds[6];
  reference->GetBounds(bounds);
  const double size = std::sqrt((bounds[1] - bounds[0]) * (bounds[1] - bounds[0]) +
    (bounds[3] - bounds[2]) * (bounds[3] - bounds[2]) +
    (bounds[5] - bounds[4]) * (bounds[5] - bounds[4]));
  const double scale = size + std::abs(pose.translation.x) + std::abs(pose.translation.y) +
    std::abs(pose.translation.z);
  double worst = 0;
  for (vtkIdType i = 0; i < n; ++i)
  {
    double a[3], b[3];
    from->GetPoint(i, a);
    to->GetPoint(i, b);
    const pbf::Vec3d moved = pose.toWorld({ a[0], a[1], a[2] });
    worst = std::max(worst, length(moved - pbf::Vec3d{ b[0], b[1], b[2] }));
  }
  return worst <= 1e-6 * scale;
}

} // namespace

//------------------------------------------------------------------------------
std::string vtkPBFObstacleMotion::Observe(const std::vector<vtkDataSet*>& obstacles, double time)
{
  std::string warning;
  if (obstacles.size() != this->Connections.size())
  {
    this->Connections.assign(obstacles.size(), Connection{});
  }
  for (std::size_t c = 0; c < obstacles.size(); ++c)
  {
    Connection& k = this->Connections[c];
    vtkDataSet* now = obstacles[c];
    pbf::SolidPose pose;
    const bool rigid = now && k.Reference && FitRigidMotion(k.Reference, now, pose);
    if (!rigid)
    {
      // A new connection, another dataset or a new shape: the reference from now on, at rest.
      // Said when the same points moved apart (a deformation), not for another dataset.
      const bool changed = k.Reference && now && now->GetNumberOfPoints() > 0 &&
        now->GetNumberOfPoints() == k.Reference->GetNumberOfPoints() &&
        now->GetNumberOfCells() == k.Reference->GetNumberOfCells();
      const int shape = k.Shape + 1;
      k = Connection{};
      k.Shape = shape;
      if (now)
      {
        k.Reference = vtkSmartPointer<vtkDataSet>::Take(now->NewInstance());
        k.Reference->DeepCopy(now);
      }
      if (changed && !this->NonRigidSaid)
      {
        this->NonRigidSaid = true;
        std::ostringstream text;
        text << "Obstacles input " << c + 1 << " changed shape at t = " << time
             << " s (its points are not a rigid motion of those seen first): its field is "
                "sampled again from the new shape and the simulation starts again from frame 0 "
                "with it. A changing shape is not simulated as such; only rigid motion is.";
        warning = text.str();
      }
    }
    const auto at = k.Seen.find(time);
    if (at != k.Seen.end())
    {
      if (!SamePose(at->second, pose))
      {
        // The same time, somewhere else: the animation itself was edited. What was seen of it
        // is stale.
        k.Seen.clear();
        k.Seen[time] = pose;
        ++k.Past;
      }
      continue;
    }
    if (!k.Seen.empty() && time < k.Seen.rbegin()->first)
    {
      ++k.Past; // between frames already seen: the motion changes where frames were computed
    }
    k.Seen[time] = pose;
  }
  return warning;
}

//------------------------------------------------------------------------------
std::string vtkPBFObstacleMotion::Key() const
{
  std::ostringstream key;
  for (const Connection& k : this->Connections)
  {
    key << " shape " << k.Shape << " motion " << k.Past;
  }
  return key.str();
}

//------------------------------------------------------------------------------
pbf::SolidMotion vtkPBFObstacleMotion::MotionOf(std::size_t c) const
{
  const Connection& k = this->Connections[c];
  pbf::SolidMotion motion;
  bool moved = false;
  for (const auto& seen : k.Seen)
  {
    moved = moved || seen.second.moving;
  }
  if (!moved || !k.Reference)
  {
    return motion;
  }
  double bounds[6];
  k.Reference->GetBounds(bounds);
  motion.pivot = { 0.5 * (bounds[0] + bounds[1]), 0.5 * (bounds[2] + bounds[3]),
    0.5 * (bounds[4] + bounds[5]) };
  for (const auto& seen : k.Seen)
  {
    // The fit carries x to R x + T; about the pivot p that is the turn R and the pivot moved by
    // T + R p - p.
    const pbf::SolidPose& pose = seen.second;
    pbf::Keyframe key;
    key.time = seen.first;
    key.rotation = pbf::Rotation::fromMatrix(pose.rotation);
    key.translation = pose.translation + key.rotation.apply(motion.pivot) - motion.pivot;
    motion.keyframes.push_back(key);
  }
  return motion;
}
