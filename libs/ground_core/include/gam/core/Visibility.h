// Ground-aware mapping for MRPT
// What a depth camera can see of a hole (issue #13): the physical limit of
// detecting a negative obstacle from a distance. Pure code.
#pragma once

namespace gam
{
/** The deepest point below the floor that a camera at height `h` above the
 * floor can see in a hole of width `w` (along the line of sight) and depth
 * `D`, whose near edge is at horizontal distance `r` from the camera: the ray
 * that grazes the near edge descends h / r per metre, so it meets the far wall
 * w * h / r below the floor; the bottom caps it. Independent of the camera's
 * tilt (which only decides whether the hole is in the field of view).
 * Returns 0 for r <= 0, h <= 0, w <= 0 or D <= 0. [m] */
inline double visibleHoleDepth(double h, double r, double w, double D)
{
	if (!(h > 0) || !(r > 0) || !(w > 0) || !(D > 0)) return 0.0;
	const double d = w * h / r;
	return d < D ? d : D;
}

/** The farthest near-edge distance at which the visible depth of such a hole
 * still reaches `threshold` (e.g. the ground band): w * h / threshold, or
 * 0 if the hole is shallower than the threshold. [m] */
inline double holeVisibilityRange(double h, double w, double D, double threshold)
{
	if (!(h > 0) || !(w > 0) || !(threshold > 0) || D < threshold) return 0.0;
	return w * h / threshold;
}
}  // namespace gam
