// Names and kinds of the problem's variables, for reports that point at some of them (the second-order
// check's flat or falling direction): "biped l_knee, spline control point 7", "contact
// 'l_landing' resultant y at t=1.2000", "contact 'landing' touch-down impulse, point 1 x".
#pragma once

#include <string>

namespace spacetime {

class SpacetimeProblem;

// What variable `index` of problem.variables() is; "variable <index>" if no layout claims it.
std::string describeVariable(const SpacetimeProblem& problem, int index);
// Whether variable `index` is a contact force (a sample's force or a touch-down's impulse).
bool isContactForce(const SpacetimeProblem& problem, int index);

}  // namespace spacetime
