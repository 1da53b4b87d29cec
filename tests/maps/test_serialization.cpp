// Versioned serialization round trips, alone and inside CMultiMetricMap.
#include <gtest/gtest.h>
#include <mrpt/io/CMemoryStream.h>
#include <mrpt/maps/CElevation25DMap.h>
#include <mrpt/maps/CGroundAwareOccupancyGrid.h>
#include <mrpt/maps/CMultiMetricMap.h>
#include <mrpt/serialization/CArchive.h>

#include "synthetic_scene.h"

using namespace mrpt::maps;
using mrpt::poses::CPose3D;

namespace
{
const CPose3D kKinect(0, 0, 1.0, 0, mrpt::DEG2RAD(25.0), 0);
std::vector<testscene::Box> boxScene()
{
	auto s = testscene::floorWithHole(-1, 6, -3, 3, 2.0, 2.4, -0.3, 0.3);
	s.push_back({1.5, 0.6, 0, 1.7, 0.8, 0.1});
	return s;
}
template <class T>
typename T::Ptr roundTrip(const T& m)
{
	mrpt::io::CMemoryStream buf;
	auto ar = mrpt::serialization::archiveFrom(buf);
	ar << m;
	buf.Seek(0);
	return ar.template ReadObject<T>();
}
}  // namespace

TEST(Serialization, ElevationMapRoundTrip)
{
	CElevation25DMap m(-2, 6, -3, 3, 0.05);
	auto mo = m.insertionOptions();
	mo.idw.radius_cells = 1;
	m.setInsertionOptions(mo);
	m.insertObservation(*testscene::renderDepth(boxScene(), kKinect));
	ASSERT_FALSE(m.isEmpty());
	auto r = roundTrip(m);
	ASSERT_TRUE(r);
	ASSERT_TRUE(r->grid().geometry() == m.grid().geometry());
	EXPECT_EQ(r->insertionOptions().idw.radius_cells, 1);
	ASSERT_EQ(r->grid().observedCount(), m.grid().observedCount());
	for (uint32_t i : m.grid().observedCells())
	{
		const auto &a = m.grid().cell(i), &b = r->grid().cell(i);
		EXPECT_EQ(a.count, b.count);
		EXPECT_EQ(a.z_min, b.z_min);
		EXPECT_EQ(a.z_max, b.z_max);
		EXPECT_EQ(a.z_sum, b.z_sum);
	}
}

TEST(Serialization, GroundAwareGridRoundTripKeepsCellsAndOptions)
{
	CGroundAwareOccupancyGrid g(-2, 6, -4, 4, 0.05);
	auto go = g.groundOptions();
	go.pipeline.rrt.iterations = 321;
	go.pipeline.ism.local_planes = false;
	g.setGroundOptions(go);
	g.insertObservation(*testscene::renderDepth(boxScene(), kKinect));
	auto r = roundTrip(g);
	ASSERT_TRUE(r);
	EXPECT_EQ(r->groundOptions().pipeline.rrt.iterations, 321);
	EXPECT_FALSE(r->groundOptions().pipeline.ism.local_planes);
	ASSERT_EQ(r->getSizeX(), g.getSizeX());
	ASSERT_EQ(r->getSizeY(), g.getSizeY());
	EXPECT_EQ(r->getRawMap(), g.getRawMap());
}

TEST(Serialization, MultiMetricMapCopyClonesBothMaps)
{
	TSetOfMetricMapInitializers inits;
	CGroundAwareOccupancyGrid::TMapDefinition d1;
	d1.groundOpts.pipeline.rrt.iterations = 250;
	inits.push_back(d1);
	CElevation25DMap::TMapDefinition d2;
	inits.push_back(d2);
	CMultiMetricMap a(inits);
	a.insertObservation(*testscene::renderDepth(boxScene(), kKinect));
	CMultiMetricMap b = a;  // MRPT copies by serializing every child
	ASSERT_EQ(b.maps.size(), 2u);
	auto ga = a.mapByClass<CGroundAwareOccupancyGrid>(), gb = b.mapByClass<CGroundAwareOccupancyGrid>();
	ASSERT_TRUE(gb);
	EXPECT_EQ(gb->groundOptions().pipeline.rrt.iterations, 250);
	EXPECT_EQ(ga->getRawMap(), gb->getRawMap());
	EXPECT_EQ(
		a.mapByClass<CElevation25DMap>()->grid().observedCount(),
		b.mapByClass<CElevation25DMap>()->grid().observedCount());
	// CMultiMetricMap::compute3DMatchingRatio averages every child's ratio
	// (MRPT's default throws "not implemented"). Neither of our maps has a 3D
	// matching: each gives 0, as the stock COccupancyGridMap2D does, so the
	// average is 0 whatever the other map holds.
	const TMatchingRatioParams mp;
	EXPECT_EQ(ga->compute3DMatchingRatio(gb.get(), CPose3D(), mp), 0.f);
	EXPECT_EQ(a.mapByClass<CElevation25DMap>()->compute3DMatchingRatio(&b, CPose3D(), mp), 0.f);
	EXPECT_EQ(a.compute3DMatchingRatio(&b, CPose3D(), mp), 0.f);
}

TEST(Serialization, PlainGridCopyIsReadableAsStockClass)
{
	CGroundAwareOccupancyGrid g(-2, 6, -4, 4, 0.05);
	g.insertObservation(*testscene::renderDepth(boxScene(), kKinect));
	const COccupancyGridMap2D plain = g;  // what tools that lack the plugin read
	mrpt::io::CMemoryStream buf;
	auto ar = mrpt::serialization::archiveFrom(buf);
	ar << plain;
	buf.Seek(0);
	auto r = ar.ReadObject<COccupancyGridMap2D>();
	ASSERT_TRUE(r);
	EXPECT_STREQ(r->GetRuntimeClass()->className, "mrpt::maps::COccupancyGridMap2D");
	EXPECT_EQ(r->getRawMap(), g.getRawMap());
}
