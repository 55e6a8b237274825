// How the datasets on the filter's Obstacles port move: each connection is kept as it was first
// seen (its reference, the shape whose field the solver samples), and every frame's request reads
// it again at the frame's time (an animated Transform, a reader with time steps) and fits the rigid
// motion from the reference to it (vtkLandmarkTransform, least squares on the same points). The
// fits become the solid's keyframes (pbf::SolidMotion), learnt as frames are asked: frames asked
// in order extend the motion past every frame already computed, so nothing computed changes; a
// frame asked between known ones changes the motion there and starts the run again. A change that
// is not rigid (other points, or a fit that misses them) takes the new shape as the reference and
// starts the run again, and is said once.
#ifndef vtkPBFObstacleMotion_h
#define vtkPBFObstacleMotion_h

#include "vtkSmartPointer.h"

#include "SolidMotion.h"

#include <map>
#include <string>
#include <vector>

class vtkDataSet;

class vtkPBFObstacleMotion
{
public:
  // Reads the connections at `time` [s]. Returns a warning to show (once per run of non-rigid
  // changes), or an empty string.
  std::string Observe(const std::vector<vtkDataSet*>& obstacles, double time);

  // What the frames depend on besides the keyframes that extend past them: the connections'
  // reference shapes and the past of their motion. Part of the playback key.
  std::string Key() const;

  // The reference dataset of connection c (what the solid's field is sampled from).
  vtkDataSet* Reference(std::size_t c) const { return this->Connections[c].Reference; }

  // The motion of connection c, its pivot the reference's centre; none while it has not moved.
  pbf::SolidMotion MotionOf(std::size_t c) const;

private:
  struct Connection
  {
    vtkSmartPointer<vtkDataSet> Reference;
    int Shape = 0;                        // counts the references taken
    std::map<double, pbf::SolidPose> Seen; // time -> the fitted pose
    int Past = 0;                         // counts the changes of the motion before its end
  };
  std::vector<Connection> Connections;
  bool NonRigidSaid = false;
};

#endif
