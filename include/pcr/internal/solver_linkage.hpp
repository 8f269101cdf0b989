#pragma once
// Where the solvers' entry points are compiled.
//
// By default pcr's core is header-only (an embedded controller links nothing): every function is
// inline and defined in its header. With PCR_COMPILED_SOLVERS defined, which the pcr::solvers
// target sets for whatever links it (pcr's own libraries, tools, tests and Python bindings), the
// headers only declare the entry points that run a whole solve (forward and inverse kinematics,
// the home solve, the stability checks, the spatial sequences' warm-then-cold solves), and
// src/solvers/solvers.cpp, which also defines PCR_SOLVERS_SOURCE, compiles them once. A file that
// calls them then no longer instantiates and optimises the whole solver again (about 100 files
// of this tree call them; clang -O3, apps/pcr/fk_command.cpp: 99 s header-only, 38 s without).
//
// PCR_SOLVER_INLINE: the entry points' linkage, on their declarations and their definitions.
// PCR_SOLVER_DEFINITIONS: 1 when this translation unit defines them.

#if defined(PCR_COMPILED_SOLVERS)
#define PCR_SOLVER_INLINE
#if defined(PCR_SOLVERS_SOURCE)
#define PCR_SOLVER_DEFINITIONS 1
#else
#define PCR_SOLVER_DEFINITIONS 0
#endif
#else
#define PCR_SOLVER_INLINE inline
#define PCR_SOLVER_DEFINITIONS 1
#endif
