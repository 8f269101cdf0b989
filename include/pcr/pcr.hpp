#pragma once
// Umbrella header of the header-only core (Eigen only).
#include "pcr/controller.hpp"
#include "pcr/implicit_kinematics.hpp"
#include "pcr/kinematics.hpp"
#include "pcr/parameters.hpp"
#include "pcr/robot.hpp"
#include "pcr/rod.hpp"
#include "pcr/scalar_traits.hpp"
#include "pcr/se2.hpp"
#include "pcr/shooting.hpp"
#include "pcr/spatial/cosserat_rod.hpp"
#include "pcr/trajectory.hpp"
