#include <gtest/gtest.h>
#include "gam/ElevationGrid.h"
TEST(ElevationGrid, EmptyAfterConstruction)
{
	gam::ElevationGrid g;
	EXPECT_EQ(g.observedCount(), 0u);
	EXPECT_EQ(g.geometry().nx, 200);
}
