// Issue #28 item 2: the depth frames of several cameras at one robot pose run
// their pipelines concurrently (option `threads`) and fuse in the order given:
// the grid must be the same, byte for byte, as inserting them one by one.
#include <gtest/gtest.h>
#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/maps/CGroundAwareOccupancyGrid.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/obs/CSensoryFrame.h>

#include <iostream>
#include <stdexcept>
#include <string>
#include <vector>

#include "synthetic_scene.h"

using namespace mrpt::maps;
using mrpt::DEG2RAD;
using mrpt::poses::CPose3D;
using testscene::Box;

namespace
{
using Obs = mrpt::obs::CObservation3DRangeScan::Ptr;

// The frames of one robot pose: a forward camera and one looking down at the
// near field (config/scenes/two_cameras.scene), at one timestamp.
struct PoseFrames
{
	CPose3D robot;
	std::vector<Obs> frames;
};

std::vector<Box> corridorScene()
{
	auto s = testscene::floorWithHole(-2, 14, -6, 6, 3.0, 3.4, -0.3, 0.3, 0.5);
	s.push_back({1.5, 0.6, 0.0, 1.7, 0.8, 0.10});
	s.push_back({6.0, -0.8, 0.0, 6.3, -0.5, 0.30});
	s.push_back({0.45, 0.15, 0.0, 0.55, 0.25, 0.06});
	return s;
}

Obs camera(const std::vector<Box>& scene, const CPose3D& robot, const CPose3D& mount, const char* label, double t)
{
	Obs o = testscene::renderDepth(scene, mount, robot, 128, 106);
	o->sensorLabel = label;
	o->timestamp = mrpt::Clock::fromDouble(t);
	return o;
}

// A walk along x with turns (8 poses, `step` apart along x, yawed by
// `yawOdd` / `yawEven` deg): the grid (created small) grows on the way,
// sometimes between the two frames of one pose.
std::vector<PoseFrames> walk(
	const std::vector<Box>& scene = corridorScene(), double step = 0.9, double yawOdd = 8.0, double yawEven = -5.0)
{
	const CPose3D forward(0.10, 0, 0.80, 0, DEG2RAD(25.0), 0);
	const CPose3D down(0.05, 0, 0.60, 0, DEG2RAD(60.0), 0);
	std::vector<PoseFrames> out;
	for (int i = 0; i < 8; i++)
	{
		const double t = 100.0 + 0.1 * i;
		PoseFrames p;
		p.robot = CPose3D(step * i, step / 18.0 * i, 0, DEG2RAD(i % 2 ? yawOdd : yawEven), 0, 0);
		p.frames.push_back(camera(scene, p.robot, forward, "KINECT", t));
		p.frames.push_back(camera(scene, p.robot, down, "KINECT_DOWN", t));
		out.push_back(p);
	}
	return out;
}

CGroundAwareOccupancyGrid makeGrid(int threads, bool mountAndDecay)
{
	// Small, so that the first frames grow it.
	CGroundAwareOccupancyGrid g(-1, 1, -1, 1, 0.05f);
	auto o = g.groundOptions();
	o.threads = threads;
	if (mountAndDecay)
	{
		// State carried from frame to frame: the measured mount (per label)
		// places the points, positive obstacles age.
		o.mount.enabled = true;
		o.mount.use_measured = true;
		o.obstacle_decay_s = 0.25;
	}
	g.setGroundOptions(o);
	return g;
}

std::vector<const mrpt::obs::CObservation*> pointers(const PoseFrames& p)
{
	std::vector<const mrpt::obs::CObservation*> v;
	for (const auto& o : p.frames) v.push_back(o.get());
	return v;
}

void expectSameGrid(const CGroundAwareOccupancyGrid& a, const CGroundAwareOccupancyGrid& b, const std::string& what)
{
	SCOPED_TRACE(what);
	ASSERT_EQ(a.getXMin(), b.getXMin());
	ASSERT_EQ(a.getXMax(), b.getXMax());
	ASSERT_EQ(a.getYMin(), b.getYMin());
	ASSERT_EQ(a.getYMax(), b.getYMax());
	ASSERT_EQ(a.getSizeX(), b.getSizeX());
	ASSERT_EQ(a.getSizeY(), b.getSizeY());
	EXPECT_TRUE(a.getRawMap() == b.getRawMap()) << "cells differ";
	EXPECT_TRUE(a.missingFloorLayer().getRawMap() == b.missingFloorLayer().getRawMap()) << "missing floor differs";
	EXPECT_EQ(a.depthFramesReceived(), b.depthFramesReceived());
	EXPECT_EQ(a.lastSensorLabel(), b.lastSensorLabel());
	EXPECT_EQ(a.lastFrame().detection.status, b.lastFrame().detection.status);
	EXPECT_EQ(a.lastFrame().points, b.lastFrame().points);
	ASSERT_EQ(a.mountChecks().size(), b.mountChecks().size());
	for (const auto& [label, m] : a.mountChecks())
	{
		const auto& n = b.mountChecks().at(label).status();
		EXPECT_EQ(m.status().frames_checked, n.frames_checked) << label;
		EXPECT_EQ(m.status().estimate.height, n.estimate.height) << label;
		EXPECT_EQ(m.status().estimate.pitch, n.estimate.pitch) << label;
	}
}

size_t occupiedCells(const COccupancyGridMap2D& g)
{
	size_t n = 0;
	for (auto c : g.getRawMap()) n += c < 0;
	return n;
}
}  // namespace

TEST(ParallelCameras, TwoCamerasThreads2IsByteIdenticalToOneByOne)
{
	const auto poses = walk();
	for (const bool stateful : {false, true})
	{
		CGroundAwareOccupancyGrid oneByOne = makeGrid(1, stateful), batch1 = makeGrid(1, stateful),
								  batch2 = makeGrid(2, stateful), batch3 = makeGrid(3, stateful),
								  fromSf = makeGrid(2, stateful);
		for (const PoseFrames& p : poses)
		{
			for (const auto& o : p.frames) oneByOne.insertObservation(*o, p.robot);
			EXPECT_TRUE(batch1.insertObservations(pointers(p), p.robot));
			EXPECT_TRUE(batch2.insertObservations(pointers(p), p.robot));
			EXPECT_TRUE(batch3.insertObservations(pointers(p), p.robot));
			mrpt::obs::CSensoryFrame sf;
			for (const auto& o : p.frames) sf.insert(o);
			EXPECT_TRUE(fromSf.insertObservations(sf, p.robot));
		}
		const std::string what = stateful ? "measured mount + obstacle decay" : "defaults";
		// The walk makes a map (not an empty comparison), and it grew the grid.
		EXPECT_GT(occupiedCells(oneByOne), 20u) << what;
		EXPECT_GT(oneByOne.getXMax(), 5.0f) << what;
		expectSameGrid(oneByOne, batch1, what + ", threads=1");
		expectSameGrid(oneByOne, batch2, what + ", threads=2");
		expectSameGrid(oneByOne, batch3, what + ", threads=3");
		expectSameGrid(oneByOne, fromSf, what + ", a CSensoryFrame, threads=2");
		// Both ways were taken: frames fused from a pipeline that ran ahead,
		// and frames run again because the first camera's evidence grew the
		// grid onto a frame-grid corner that differs in its last bits.
		std::cout << "[parallel] " << what << ": threads=2 " << batch2.parallelStats().ran_ahead
				  << " frames fused from a pipeline that ran ahead, " << batch2.parallelStats().run_again
				  << " run again\n";
		EXPECT_EQ(batch1.parallelStats().ran_ahead + batch1.parallelStats().run_again, 0u);
		EXPECT_GE(batch2.parallelStats().ran_ahead, 10u) << what;
		EXPECT_GE(batch2.parallelStats().run_again, 1u) << what;
		EXPECT_EQ(batch2.parallelStats().ran_ahead + batch2.parallelStats().run_again, 2 * poses.size()) << what;
	}
}

TEST(ParallelCameras, RampPatchesRememberedPerCameraStayByteIdentical)
{
	// Each camera's pipeline remembers the ramp patches its frames fitted
	// (patch_memory): a frame that ran ahead and runs again must count once.
	// A 7 deg ramp beside the walk, as steps of 1 cm every 8 cm (under d_pth
	// and traversable_step: the tree fits it as one sloped patch), 0.9 m wide.
	auto scene = corridorScene();
	for (int k = 0; k < 14; k++) scene.push_back({2.0 + 0.08 * k, -1.6, 0.0, 3.6, -0.7, 0.01 * (k + 1)});
	auto poses = walk(scene, 0.2, 4.0, -3.0);
	// Two cameras that both see the ramp (the second a little to the right):
	// the first's evidence grows the grid, so the second's frame, which fits
	// patches, is the one run again.
	const CPose3D right(0.10, -0.05, 0.80, DEG2RAD(-6.0), DEG2RAD(25.0), 0);
	for (PoseFrames& p : poses)
		p.frames[1] = camera(scene, p.robot, right, "KINECT_RIGHT", mrpt::Clock::toDouble(p.frames[0]->timestamp));
	CGroundAwareOccupancyGrid oneByOne = makeGrid(1, false), batch2 = makeGrid(2, false);
	size_t remembered = 0, fitted = 0;
	for (const PoseFrames& p : poses)
	{
		for (const auto& o : p.frames)
		{
			oneByOne.insertObservation(*o, p.robot);
			remembered += oneByOne.lastFrame().remembered_planes.size();
		}
		EXPECT_TRUE(batch2.insertObservations(pointers(p), p.robot));
		// Each camera's memory as one by one: a frame run twice (its first
		// run not taken) counted once, its path not walked twice.
		for (const auto& o : p.frames)
		{
			const gam::PatchMemory *a = oneByOne.rememberedPatches(o->sensorLabel),
								   *b = batch2.rememberedPatches(o->sensorLabel);
			ASSERT_TRUE(a && b) << o->sensorLabel;
			EXPECT_EQ(a->travelled(), b->travelled()) << o->sensorLabel;
			ASSERT_EQ(a->size(), b->size()) << o->sensorLabel;
			for (size_t k = 0; k < a->size(); k++)
			{
				EXPECT_EQ(a->patch(k).frames, b->patch(k).frames) << o->sensorLabel << " patch " << k;
				EXPECT_EQ(a->patch(k).seen_at, b->patch(k).seen_at) << o->sensorLabel << " patch " << k;
				EXPECT_EQ(a->patch(k).plane.d, b->patch(k).plane.d) << o->sensorLabel << " patch " << k;
				fitted += size_t(a->patch(k).frames);
			}
		}
	}
	std::cout << "[parallel] ramp: " << remembered << " remembered patches applied one by one; threads=2 "
			  << batch2.parallelStats().ran_ahead << " ran ahead, " << batch2.parallelStats().run_again
			  << " run again\n";
	EXPECT_GT(remembered, 0u) << "the walk must exercise the memory";
	EXPECT_GT(fitted, 0u) << "the memory must hold patches to compare";
	EXPECT_GE(batch2.parallelStats().run_again, 1u);
	expectSameGrid(oneByOne, batch2, "ramp, threads=2");
}

TEST(ParallelCameras, SameLabelTwiceAndAfterEachSeeEveryFrameInOrder)
{
	// Two frames of one camera in a set: the second needs the first's mount
	// update and the same pipeline, so it runs in order; afterEach sees each
	// frame's own result.
	const auto poses = walk();
	CGroundAwareOccupancyGrid oneByOne = makeGrid(1, true), batch = makeGrid(2, true);
	for (const PoseFrames& p : poses)
	{
		std::vector<const mrpt::obs::CObservation*> v = pointers(p);
		v.push_back(p.frames[0].get());
		v.push_back(nullptr);  // skipped
		std::vector<std::string> oneLabels, batchLabels;
		std::vector<size_t> onePoints, batchPoints;
		for (const auto* o : v)
			if (o)
			{
				oneByOne.insertObservation(*o, p.robot);
				oneLabels.push_back(oneByOne.lastSensorLabel());
				onePoints.push_back(oneByOne.lastFrame().points);
			}
		batch.insertObservations(v, p.robot, [&](size_t i) {
			EXPECT_TRUE(v[i] != nullptr);
			batchLabels.push_back(batch.lastSensorLabel());
			batchPoints.push_back(batch.lastFrame().points);
		});
		EXPECT_EQ(oneLabels, batchLabels);
		EXPECT_EQ(onePoints, batchPoints);
	}
	expectSameGrid(oneByOne, batch, "same label twice");
}

TEST(ParallelCameras, AMalformedFrameThrowsInItsTurn)
{
	// The frame before it is fused, the one after it is not: as one by one.
	const auto poses = walk();
	auto bad = mrpt::obs::CObservation3DRangeScan::Create(*poses[0].frames[1]);
	bad->sensorLabel = "BROKEN";
	bad->cameraParams.ncols = 7;  // the image is 128 wide
	bad->cameraParams.nrows = 7;
	bad->cameraParams.setIntrinsicParamsFromValues(0, 0, 0, 0);  // and no usable intrinsics
	CGroundAwareOccupancyGrid oneByOne = makeGrid(1, false), batch = makeGrid(2, false);
	std::vector<const mrpt::obs::CObservation*> v{poses[0].frames[0].get(), bad.get(), poses[0].frames[1].get()};
	bool oneThrew = false, batchThrew = false;
	try
	{
		for (const auto* o : v) oneByOne.insertObservation(*o, poses[0].robot);
	}
	catch (const std::exception&)
	{
		oneThrew = true;
	}
	try
	{
		batch.insertObservations(v, poses[0].robot);
	}
	catch (const std::exception&)
	{
		batchThrew = true;
	}
	EXPECT_TRUE(oneThrew);
	EXPECT_EQ(oneThrew, batchThrew);
	expectSameGrid(oneByOne, batch, "malformed frame");
	// The grid goes on as before.
	for (const auto& o : poses[1].frames) oneByOne.insertObservation(*o, poses[1].robot);
	batch.insertObservations(pointers(poses[1]), poses[1].robot);
	expectSameGrid(oneByOne, batch, "after the malformed frame");
}

TEST(ParallelCameras, ThreadsOptionLoadSaveAndRange)
{
	CGroundAwareOccupancyGrid::TGroundAwareOptions o;
	EXPECT_EQ(o.threads, 1);
	o.threads = 2;
	mrpt::config::CConfigFileMemory mem;
	o.saveToConfigFile(mem, "g");
	CGroundAwareOccupancyGrid::TGroundAwareOptions back;
	back.loadFromConfigFile(mem, "g");
	EXPECT_EQ(back.threads, 2);

	for (const char* bad : {"0", "65", "-1"})
	{
		mrpt::config::CConfigFileMemory ini(std::string("[g]\nthreads=") + bad + "\n");
		CGroundAwareOccupancyGrid::TGroundAwareOptions x;
		try
		{
			x.loadFromConfigFile(ini, "g");
			ADD_FAILURE() << "threads=" << bad << " was accepted";
		}
		catch (const std::invalid_argument& e)
		{
			EXPECT_NE(std::string(e.what()).find("threads"), std::string::npos) << e.what();
		}
	}
	CGroundAwareOccupancyGrid g;
	auto opts = g.groundOptions();
	opts.threads = 0;
	EXPECT_THROW(g.setGroundOptions(opts), std::invalid_argument);
	EXPECT_EQ(g.groundOptions().threads, 1);
}

TEST(ParallelCameras, ACopiedGridHasItsOwnWorkers)
{
	// clone() copies the grid: the copy must not share the pool's threads.
	const auto poses = walk();
	CGroundAwareOccupancyGrid a = makeGrid(2, false);
	a.insertObservations(pointers(poses[0]), poses[0].robot);
	CGroundAwareOccupancyGrid b = a;
	a.insertObservations(pointers(poses[1]), poses[1].robot);
	b.insertObservations(pointers(poses[1]), poses[1].robot);
	expectSameGrid(a, b, "copy");
}
