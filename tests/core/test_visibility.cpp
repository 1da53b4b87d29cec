// Ground-aware mapping for MRPT
// The visibility limit of a hole (issue #13), by hand from the geometry.
#include <gtest/gtest.h>

#include "gam/core/Visibility.h"

using namespace gam;

TEST(Visibility, DeepestVisiblePointOfAHoleByHand)
{
	// Kinect 0.8 m high, a 15 cm wide outlet whose near edge is 2.4 m away:
	// the grazing ray descends 0.8 / 2.4 = 1/3 m per metre, so 0.15 m further
	// it is 0.15 / 3 = 0.05 m below the floor.
	EXPECT_NEAR(visibleHoleDepth(0.8, 2.4, 0.15, 0.08), 0.05, 1e-12);
	// A 3 cm deep outlet: the bottom is seen (0.05 > 0.03), so 0.03.
	EXPECT_DOUBLE_EQ(visibleHoleDepth(0.8, 2.4, 0.15, 0.03), 0.03);
	// Twice as far (4.8 m): half the depth, 0.025.
	EXPECT_NEAR(visibleHoleDepth(0.8, 4.8, 0.15, 0.08), 0.025, 1e-12);
	// A 30 cm hole at 1 m seen from 1.0 m: 0.3 * 1.0 / 1.0 = 0.3, capped by 0.2.
	EXPECT_DOUBLE_EQ(visibleHoleDepth(1.0, 1.0, 0.3, 0.2), 0.2);
	EXPECT_DOUBLE_EQ(visibleHoleDepth(0.8, 0.0, 0.15, 0.08), 0.0);
	EXPECT_DOUBLE_EQ(visibleHoleDepth(0.8, 2.0, 0.0, 0.08), 0.0);
}

TEST(Visibility, RangeAtWhichTheVisibleDepthReachesTheBand)
{
	// The 15 cm outlet from 0.8 m against a 3 cm band: 0.15 * 0.8 / 0.03 = 4.0 m.
	EXPECT_NEAR(holeVisibilityRange(0.8, 0.15, 0.08, 0.03), 4.0, 1e-12);
	// 10 cm wide: 0.1 * 0.8 / 0.03 = 2.6667 m.
	EXPECT_NEAR(holeVisibilityRange(0.8, 0.10, 0.05, 0.03), 2.6666667, 1e-6);
	// A 2 cm deep hole never shows 3 cm of depth.
	EXPECT_DOUBLE_EQ(holeVisibilityRange(0.8, 0.15, 0.02, 0.03), 0.0);
	// Consistent with visibleHoleDepth at that range.
	EXPECT_NEAR(visibleHoleDepth(0.8, 4.0, 0.15, 0.08), 0.03, 1e-12);
}
