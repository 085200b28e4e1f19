// Explicit instantiations of the dynamics algorithms for double, so that every user of the
// double versions shares one compiled copy.
#include "dynamics/algorithms.h"

namespace spacetime {

template void forwardKinematics<double, double>(const Model<double>&, Data<double>&,
                                                const double*);
template void forwardKinematics<double, double>(const Model<double>&, Data<double>&,
                                                const double*, const double*, const double*);
template const VecX<double>& rnea<double, double>(const Model<double>&, Data<double>&,
                                                  const double*, const double*, const double*,
                                                  const std::vector<PointForce<double>>&, bool, bool);
template MatX<double> crba<double, double>(const Model<double>&, Data<double>&, const double*);
template VecX<double> aba<double, double>(const Model<double>&, Data<double>&, const double*,
                                          const double*, const double*,
                                          const std::vector<PointForce<double>>&);

}  // namespace spacetime
