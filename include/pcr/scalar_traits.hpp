#pragma once
// Plain value of a scalar, for decisions that must not be differentiated (branch selection,
// convergence tests). Specialise ScalarTraits for other scalar types (pcr/calib/jet_traits.hpp
// does it for ceres::Jet); a struct specialisation is found by two-phase lookup, an overload is
// not.

namespace pcr {

template <class T, class Enable = void>
struct ScalarTraits {
  static double value(const T& x) { return static_cast<double>(x); }
};

template <class T>
double scalar_value(const T& x) {
  return ScalarTraits<T>::value(x);
}

}  // namespace pcr
