/**
 * @class   vtkPBFRigidBody
 * @brief   Marks a dataset as a rigid body that the fluid of vtkPBFSimulation moves.
 *
 * The output is the input, unchanged, with field data that vtkPBFSimulation reads when the
 * dataset arrives on its Obstacles port: `PBFBodyDensity` (Density [kg/m^3]), `PBFBodyFreeAxes`
 * and `PBFBodyTurns` (its freedoms), `PBFBodyRelease` (Release [s]) and, when Name is not empty,
 * `PBFBodyName`: a scene file's "density", "degreesOfFreedom", "release" and "name". Such an
 * obstacle is a body: its mass, centre of mass and inertia come
 * from its closed surface and the density, and the fluid's force and torque and gravity move it
 * (pbf::Simulation's bodies; the Diagnostics table and the particles' field data give its pose and
 * velocities under Name). Without this filter an obstacle stands still, or moves as its input
 * moves (an animated Transform); a body's input must not move. A density that is not a positive
 * number, or a Release that is not a finite time >= 0, is an error of the simulation naming the
 * obstacle and the value, not of this filter: the setters store what was typed.
 */
#ifndef vtkPBFRigidBody_h
#define vtkPBFRigidBody_h

#include "PBFFiltersModule.h" // For export macro
#include "vtkPassInputTypeAlgorithm.h"

class PBFFILTERS_EXPORT vtkPBFRigidBody : public vtkPassInputTypeAlgorithm
{
public:
  static vtkPBFRigidBody* New();
  vtkTypeMacro(vtkPBFRigidBody, vtkPassInputTypeAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  ///@{
  /**
   * The body's density [kg/m^3]; water's is 1000. Default 500.
   */
  vtkSetMacro(Density, double);
  vtkGetMacro(Density, double);
  ///@}

  ///@{
  /**
   * What the Diagnostics columns and field data call the body; empty (the default): the
   * simulation's name for the obstacle ("Obstacles input k of n").
   */
  vtkSetStringMacro(Name);
  vtkGetStringMacro(Name);
  ///@}

  ///@{
  /**
   * The world axes x, y, z its centre moves along (non-zero: free); a held axis keeps the
   * centre's coordinate where it was given. Default 1 1 1; 0 1 0 with Turns off is a body on a
   * vertical guide (a drop test that heaves only).
   */
  vtkSetVector3Macro(FreeAxes, int);
  vtkGetVector3Macro(FreeAxes, int);
  ///@}

  ///@{
  /**
   * Whether it turns. Default on.
   */
  vtkSetMacro(Turns, bool);
  vtkGetMacro(Turns, bool);
  vtkBooleanMacro(Turns, bool);
  ///@}

  ///@{
  /**
   * The time until which it is held at rest where it is given, the fluid pushing on it, and
   * released then [s] (a drop test's hold while the water settles). Default 0.
   */
  vtkSetMacro(Release, double);
  vtkGetMacro(Release, double);
  ///@}

protected:
  vtkPBFRigidBody();
  ~vtkPBFRigidBody() override;

  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;

private:
  vtkPBFRigidBody(const vtkPBFRigidBody&) = delete;
  void operator=(const vtkPBFRigidBody&) = delete;

  double Density;
  char* Name;
  int FreeAxes[3];
  bool Turns;
  double Release;
};

#endif
