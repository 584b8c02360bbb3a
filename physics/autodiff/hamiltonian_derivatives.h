// Derivatives of a system's H of any order at a batch of states: the library's systems' H
// written a second time with the engine's ops (engine_hamiltonian), differentiated by the engine
// as a model's H is (autodiff/functional.h row_jacobian, repeated); an ExpressionSystem's
// symbolically (ExpressionSystem::derivatives). What hnn.autodiff gives on hnn.systems
// (apps/python/autodiff.cpp).
#pragma once

#include <optional>

#include "physics/autodiff/autodiff_system.h"

namespace hnn::physics {

/// `system`'s H written with the engine's ops, equal to its hamiltonian_batch to rounding, for
/// Spring, Pendulum, NBody, DoublePendulum, HenonHeiles and AutodiffSystem; nullopt for others.
std::optional<AutodiffHamiltonian> engine_hamiltonian(const System& system);

/// d^order H / dx^order at each row of x: R x dim^order, row r's entry d^k H / dx_i1 ... dx_ik
/// at column i1 dim^(k-1) + ... + ik (each new index last, as hnn.autodiff lays them out).
/// Order 0 is H. An ExpressionSystem's symbolically, the others' by engine_hamiltonian. Throws
/// std::invalid_argument for a negative order, a system with neither, a batch whose column count
/// is not dim(), or naming the row where a derivative is not finite.
Batch hamiltonian_derivatives(const System& system, const BatchView& x, int order);

}  // namespace hnn::physics
