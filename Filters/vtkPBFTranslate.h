// The filter's input as the fluid's initial particles, and the solver's messages in the
// words of the GUI: the two places where vtkPBFSimulation translates between VTK/ParaView and
// the solver.
#ifndef vtkPBFTranslate_h
#define vtkPBFTranslate_h

#include "Stepper.h"

#include <string>

class vtkPointSet;

// Point i becomes particle i, with the initial velocity of a 3-component point array "velocity"
// when there is one. Throws pbf::InvalidInput for fewer than 2 points, a non-finite coordinate or
// velocity, or a "velocity" array of another shape.
pbf::ParticleBatch vtkPBFBatchFromInput(vtkPointSet* input);

// The solver's messages name its own fields (timeStep, cflNumber, solverIterations); a ParaView
// user sees properties. Advice about a field becomes advice about the properties that set it,
// then every remaining field name becomes its property's label.
std::string vtkPBFInUserTerms(std::string text);

// What is wrong with the time properties, in the GUI's words and with the value as typed; empty
// when nothing is. MaxTimeStep matters with automatic steps, SubstepsPerFrame with fixed ones.
std::string vtkPBFInvalidTimeProperty(double frameInterval, int numberOfFrames, bool automatic,
  int substepsPerFrame, double maxTimeStep);

#endif
