// Rigid bodies as constrained point masses (the peer's BodyGraph.add_extended_nd): the centre
// of mass and the tips of three unit body axes, with the gyroscope and the rotor.
#pragma once

#include "physics/constrained/constrained_system.h"

namespace hnn::physics::constrained {

/// The ZXZ (intrinsic) Euler rotation R = Rz(a) Rx(b) Rz(c) and its time derivative for the
/// angle rates, as scipy's Rotation.from_euler('ZXZ') and the peer's euler2frame.
void euler_frame(const Eigen::Vector3d& angles, const Eigen::Vector3d& rates, Eigen::Matrix3d& r,
                 Eigen::Matrix3d& r_dot);

/// A body of mass m and second moments I_k = m moments_k along its axes: points 0 (centre) and
/// k = 1..3 (centre + R e_k), distances 1 from the centre and sqrt(2) between tips. Kinetic
/// energy m |v_0|^2 / 2 + sum_k I_k |v_k - v_0|^2 / 2, so M = [[m + sum I, -I^T], [-I, diag I]].
ConstrainedSpec rigid_body_spec(const std::string& name, double mass,
                                const Eigen::Vector3d& moments);

/// (centre, angles) with their rates -> the body's 4 points and velocities, one row (24).
void rigid_body_points(const Eigen::Vector3d& centre, const Eigen::Vector3d& centre_rate,
                       const Eigen::Vector3d& angles, const Eigen::Vector3d& rates, double* z);

/// Gyroscope(): mass 0.1, moments 100 x the diagonal second moments of the peer's gyro.obj,
/// pinned at its tip (body point -com) to the origin, gravity -z; dt 0.02, horizon 2. Sampler:
/// Euler angles U(-1.5, 1.5), rates U(-4.5, 4.5), U(-0.3, 0.3) and +-(N(0, 1) + 7) 1.5 (spin),
/// the body moved so that its tip is at rest at the origin.
ConstrainedSystem gyroscope();

/// Rotor(): a free body of mass 0.1 with the diagonal second moments of the peer's rotor.obj,
/// no potential; dt 0.05, horizon 5. Sampler: centre, Euler angles and all their rates
/// clamp(2 N(0, 1), -3, 3), the centre's position and velocity scaled by 0.1.
ConstrainedSystem rotor();

}  // namespace hnn::physics::constrained
