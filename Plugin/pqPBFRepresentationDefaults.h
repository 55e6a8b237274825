// Display defaults that proxy XML hints cannot express in ParaView 5.11, applied in the GUI when a
// Position Based Fluids source or filter is shown:
// - the Point Gaussian radius is half the ParticleSpacing, so that neighbouring particles touch
//   and the fluid reads as a volume (the representation's own default is 0.5% of the bounds),
//   and follows the spacing when it changes unless the user set a radius of their own;
// - the "velocity" color map grows every time step, because frame 0 is at rest (all speeds 0)
//   and a range taken on Apply would saturate as soon as the animation plays, and starts again
//   from the data when the scene (Preset, SceneFile) changes;
// - the Diagnostics table (output port 1) in a Line Chart View plots the two density errors (in
//   percent) against Time, instead of every column on one axis.
#ifndef pqPBFRepresentationDefaults_h
#define pqPBFRepresentationDefaults_h

#include <QObject>

class pqRepresentation;

class pqPBFRepresentationDefaults : public QObject
{
  Q_OBJECT
  typedef QObject Superclass;

public:
  pqPBFRepresentationDefaults(QObject* parent = nullptr);
  ~pqPBFRepresentationDefaults() override;

  // Called by the plugin's auto-start interface when the plugin is loaded and unloaded.
  void startup();
  void shutdown();

private Q_SLOTS:
  void onRepresentationAdded(pqRepresentation* representation);

private:
  Q_DISABLE_COPY(pqPBFRepresentationDefaults)
};

#endif
