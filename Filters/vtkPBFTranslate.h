// The filter's input as the fluid's initial particles, and the solver's messages in the
// words of the GUI: the two places where vtkPBFSimulation translates between VTK/ParaView and
// the solver.
#ifndef vtkPBFTranslate_h
#define vtkPBFTranslate_h

#include "Stepper.h"

#include <string>

#include "vtkType.h"

class vtkPointSet;

// Point i becomes particle first + i, with the initial velocity of a 3-component point array
// "velocity" when there is one. Throws pbf::InvalidInput for fewer than 2 points in all (`total`,
// the input's own count when negative), a non-finite coordinate or velocity, or a "velocity"
// array of another shape. `first` and `total` place a rank's piece of a parallel input in the
// whole, so that a message names the point as the whole input numbers it.
pbf::ParticleBatch vtkPBFBatchFromInput(
  vtkPointSet* input, vtkIdType first = 0, vtkIdType total = -1);

// The solver's messages name its own fields (timeStep, cflNumber, solverIterations); a ParaView
// user sees properties. Advice about a field becomes advice about the properties that set it,
// then every remaining field name becomes its property's label.
std::string vtkPBFInUserTerms(std::string text);

// What is wrong with the time properties, in the GUI's words and with the value as typed; empty
// when nothing is. MaxTimeStep matters with automatic steps, SubstepsPerFrame with fixed ones.
std::string vtkPBFInvalidTimeProperty(double frameInterval, int numberOfFrames, bool automatic,
  int substepsPerFrame, double maxTimeStep);

#endif
