// Ground-aware mapping for MRPT
// The cell labels of the ground-truth files: written by the simulator
// (libs/ground_sim), read by the evaluator (libs/ground_eval). One
// vocabulary, so the two can never disagree on a name or a number.
#pragma once

#include <cstdint>

namespace gam
{
enum class GroundTruthLabel : uint8_t
{
	Free = 0,
	Obstacle = 1,
	Drop = 2,
	Unobserved = 3
};

/** "free", "obstacle", "drop", "unobserved" (as in the _gt_labels.csv files). */
inline const char* labelName(GroundTruthLabel l)
{
	switch (l)
	{
		case GroundTruthLabel::Free: return "free";
		case GroundTruthLabel::Obstacle: return "obstacle";
		case GroundTruthLabel::Drop: return "drop";
		case GroundTruthLabel::Unobserved: return "unobserved";
	}
	return "?";
}
}  // namespace gam
