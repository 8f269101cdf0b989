#pragma once
// Lets the core's templated code take plain values of ceres::Jet (see pcr/scalar_traits.hpp).

#include <ceres/jet.h>

#include "pcr/scalar_traits.hpp"

namespace pcr {

template <class T, int N>
struct ScalarTraits<ceres::Jet<T, N>> {
  static double value(const ceres::Jet<T, N>& x) { return ScalarTraits<T>::value(x.a); }
};

}  // namespace pcr
