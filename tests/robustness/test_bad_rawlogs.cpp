// Bad rawlogs through the mapper's streaming reader (gam::mapper::RawlogFrameReader)
// and every frame it yields into every map class: empty files, files cut in the middle
// of an object, flipped bytes, objects of unexpected classes. Each gives frames and
// then a std::runtime_error naming the entry, or a clean end; never a crash.
// Already covered elsewhere (not repeated): tests/mapper BadInputsGiveOneLineErrors
// (missing file, a text file, an odometry-only rawlog).
#include <gam/mapper/Mapper.h>
#include <gam/mapper/RawlogFrames.h>
#include <gtest/gtest.h>
#include <mrpt/io/CFileGZOutputStream.h>
#include <mrpt/io/CFileOutputStream.h>
#include <mrpt/io/CMemoryStream.h>
#include <mrpt/maps/CSimpleMap.h>
#include <mrpt/obs/CActionCollection.h>
#include <mrpt/obs/CActionRobotMovement2D.h>
#include <mrpt/obs/CObservationGPS.h>
#include <mrpt/obs/CObservationImage.h>
#include <mrpt/obs/CObservationOdometry.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/poses/CPose2D.h>
#include <mrpt/poses/CPosePDFGaussian.h>
#include <mrpt/serialization/CArchive.h>

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include "robustness_helpers.h"

namespace fs = std::filesystem;
using namespace gam::mapper;

namespace
{
const std::string kTmp = std::string(GAM_TEST_TMP_DIR) + "/rawlogs_p" + std::to_string(getpid());

std::string tmpFile(const std::string& name)
{
	fs::create_directories(kTmp);
	return kTmp + "/" + name;
}

std::string slurp(const std::string& f)
{
	std::ifstream i(f, std::ios::binary);
	std::ostringstream s;
	s << i.rdbuf();
	return s.str();
}
void spit(const std::string& f, const std::string& bytes) { std::ofstream(f, std::ios::binary) << bytes; }

/** Observations-format rawlog: per frame odometry + a small depth frame + a 2D scan. */
template <class Stream>
void writeObsRawlog(Stream& out, int frames)
{
	auto ar = mrpt::serialization::archiveFrom(out);
	for (int k = 0; k < frames; k++)
	{
		mrpt::obs::CObservationOdometry odo;
		odo.odometry = mrpt::poses::CPose2D(0.2 * k, 0, 0);
		ar << odo;
		auto o = testscene::renderDepth(robust::floorAndBox(), robust::kMount, {}, 64, 48);
		ar << *o;
		mrpt::obs::CObservation2DRangeScan s;
		s.aperture = float(M_PI / 4);
		s.maxRange = 50;
		s.resizeScan(16);
		for (size_t i = 0; i < 16; i++)
		{
			s.setScanRange(i, 3.0f);
			s.setScanRangeValidity(i, true);
		}
		ar << s;
	}
}

std::string plainRawlog(int frames)
{
	const std::string f = tmpFile("plain_" + std::to_string(frames) + ".rawlog");
	mrpt::io::CFileOutputStream out(f);
	writeObsRawlog(out, frames);
	return f;
}

struct ReadOutcome
{
	size_t frames = 0;
	bool threw = false;
	std::string error;
};

/** Reads every frame and inserts it into a fresh map of every class (exceptions
 * from the maps are acceptable answers to corrupt observations). */
ReadOutcome readAll(const std::string& path)
{
	ReadOutcome r;
	auto maps = robust::allMaps();
	try
	{
		RawlogFrameReader rd(path);
		Frame f;
		while (rd.next(f))
		{
			r.frames++;
			for (auto& m : maps)
			{
				try
				{
					m.map->insertObservation(*f.obs, f.robotPose);
				}
				catch (const std::exception&)
				{
				}
			}
		}
	}
	catch (const std::runtime_error& e)
	{
		r.threw = true;
		r.error = e.what();
	}
	return r;
}

/** Writes `bytes` as a rawlog and reads it all: an error whose message holds `what`. */
void expectReadError(const std::string& bytes, const std::string& what)
{
	const std::string f = tmpFile("corrupt.rawlog");
	spit(f, bytes);
	const auto r = readAll(f);
	EXPECT_TRUE(r.threw) << what;
	EXPECT_NE(r.error.find(what), std::string::npos) << r.error;
}
}  // namespace

TEST(RobustRawlogs, EmptyFilesEndCleanlyWithNoFrames)
{
	const std::string empty = tmpFile("empty.rawlog");
	spit(empty, "");
	auto r = readAll(empty);
	EXPECT_FALSE(r.threw) << r.error;
	EXPECT_EQ(r.frames, 0u);
	// A gzip stream holding nothing.
	const std::string emptyGz = tmpFile("empty_gz.rawlog");
	{
		mrpt::io::CFileGZOutputStream o(emptyGz);
	}
	r = readAll(emptyGz);
	EXPECT_FALSE(r.threw) << r.error;
	EXPECT_EQ(r.frames, 0u);
	// The mapper says so (exit code 1 in the app).
	MapperOptions mo;
	mo.rawlogPath = empty;
	mo.outDir = tmpFile("out_empty");
	mo.configText = "[map]\ngroundAwareGrid_count=1\n";
	mo.progress = false;
	Mapper m(mo);
	try
	{
		m.run();
		ADD_FAILURE() << "an empty rawlog gave maps";
	}
	catch (const RunError& e)
	{
		EXPECT_NE(std::string(e.what()).find("no usable observation"), std::string::npos) << e.what();
	}
}

TEST(RobustRawlogs, FileCutInTheMiddleOfAnObjectIsAnErrorNamingTheEntry)
{
	const std::string good = plainRawlog(3);
	const std::string bytes = slurp(good);
	ASSERT_GT(bytes.size(), 1000u);
	const auto full = readAll(good);
	ASSERT_FALSE(full.threw) << full.error;
	ASSERT_EQ(full.frames, 6u);
	// Cut everywhere (in steps, plus the first and last bytes).
	size_t clean = 0, errors = 0;
	std::vector<size_t> cuts = {1, 2, 5, 10, bytes.size() - 1, bytes.size() - 2};
	for (size_t c = 17; c < bytes.size(); c += 97) cuts.push_back(c);
	const std::string cut = tmpFile("cut.rawlog");
	for (size_t c : cuts)
	{
		spit(cut, bytes.substr(0, c));
		const auto r = readAll(cut);
		EXPECT_LE(r.frames, full.frames) << "cut at " << c;
		if (r.threw)
		{
			errors++;
			EXPECT_NE(r.error.find("entry"), std::string::npos) << r.error;
			EXPECT_NE(r.error.find("corrupt"), std::string::npos) << "cut at " << c << ": " << r.error;
		}
		else
			clean++;
	}
	EXPECT_GT(errors, cuts.size() / 2) << "a cut inside an object must not pass as a clean end";
}

TEST(RobustRawlogs, FlippedBytesGiveFramesThenAnErrorNamingTheEntryOrACleanEnd)
{
	// The right outcome for a rawlog with 1-4 flipped bytes: no crash (the
	// process survives 150 mutants), at most the frames the file holds, and
	// either a clean end or a std::runtime_error that names the entry and says
	// "corrupt". Flipped bytes inside float data read as other values; those in
	// a class name, a version or a length must be reported: some are.
	const std::string good = plainRawlog(2);
	const std::string bytes = slurp(good);
	const auto full = readAll(good);
	ASSERT_FALSE(full.threw) << full.error;
	ASSERT_EQ(full.frames, 4u);
	std::mt19937 rng(12345);
	const std::string bad = tmpFile("flipped.rawlog");
	size_t errors = 0, frames = 0;
	for (int t = 0; t < 150; t++)
	{
		std::string b = bytes;
		const int n = 1 + int(rng() % 4);
		for (int k = 0; k < n; k++) b[rng() % b.size()] ^= char(1 + rng() % 255);
		spit(bad, b);
		if (getenv("GAM_ROBUST_DEBUG")) fprintf(stderr, "mutant %d\n", t), spit(bad + "." + std::to_string(t), b);
		const auto r = readAll(bad);
		EXPECT_LE(r.frames, full.frames) << "mutant " << t;
		if (r.threw)
		{
			EXPECT_NE(r.error.find("entry"), std::string::npos) << "mutant " << t << ": " << r.error;
			EXPECT_NE(r.error.find("corrupt"), std::string::npos) << "mutant " << t << ": " << r.error;
		}
		errors += r.threw;
		frames += r.frames;
	}
	RecordProperty("mutants_with_errors", int(errors));
	EXPECT_GT(errors, 0u) << "no mutant of 150 was reported as corrupt (" << frames << " frames read in total)";
}

TEST(RobustRawlogs, CorruptGzipStreamIsAnError)
{
	const std::string gz = tmpFile("good.rawlog.gz");
	{
		mrpt::io::CFileGZOutputStream out(gz);
		writeObsRawlog(out, 2);
	}
	const std::string bytes = slurp(gz);
	ASSERT_GT(bytes.size(), 100u);
	// Garbage in the middle of the deflate stream, and a cut one.
	std::string b = bytes;
	for (size_t i = bytes.size() / 2; i < bytes.size() / 2 + 16; i++) b[i] = char(0xA5);
	const std::string bad = tmpFile("bad.rawlog.gz");
	spit(bad, b);
	auto r = readAll(bad);
	EXPECT_TRUE(r.threw) << r.frames << " frames, no error";
	spit(bad, bytes.substr(0, bytes.size() / 2));
	r = readAll(bad);
	EXPECT_TRUE(r.threw) << r.frames << " frames, no error";
}

TEST(RobustRawlogs, ObjectsOfUnexpectedClassesAreSkipped)
{
	const std::string f = tmpFile("odd_classes.rawlog");
	{
		mrpt::io::CFileGZOutputStream out(f);
		auto ar = mrpt::serialization::archiveFrom(out);
		ar << mrpt::poses::CPose2D(1, 2, 0.3);  // not an observation at all
		mrpt::maps::CSimpleMap sm;
		ar << sm;
		mrpt::obs::CObservationImage img;
		img.image.resize(8, 8, mrpt::img::CH_GRAY);
		ar << img;
		mrpt::obs::CObservationGPS gps;
		ar << gps;
		// A sensory frame with an image, an empty 3D scan and a real one.
		mrpt::obs::CSensoryFrame sf;
		sf.insert(mrpt::obs::CObservationImage::Create(img));
		sf.insert(mrpt::obs::CObservation3DRangeScan::Create());
		sf.insert(testscene::renderDepth(robust::floorAndBox(), robust::kMount, {}, 64, 48));
		ar << sf;
		mrpt::obs::CActionCollection acts;  // no movement estimation in it
		ar << acts;
	}
	RawlogFrameReader rd(f);
	Frame fr;
	size_t n = 0;
	while (rd.next(fr))
	{
		n++;
		EXPECT_TRUE(IS_CLASS(*fr.obs, mrpt::obs::CObservation3DRangeScan));
	}
	EXPECT_EQ(n, 1u);
	EXPECT_EQ(rd.entriesRead(), 6u);
	EXPECT_GE(rd.skippedObservations(), 5u);

	// Only unexpected classes: the mapper says there is nothing to map.
	const std::string g = tmpFile("only_odd.rawlog");
	{
		mrpt::io::CFileGZOutputStream out(g);
		auto ar = mrpt::serialization::archiveFrom(out);
		ar << mrpt::poses::CPose2D(1, 2, 0.3);
		mrpt::obs::CObservationImage img;
		ar << img;
	}
	MapperOptions mo;
	mo.rawlogPath = g;
	mo.outDir = tmpFile("out_odd");
	mo.configText = "[map]\nCElevation25DMap_count=1\n";
	mo.progress = false;
	Mapper m(mo);
	EXPECT_THROW(m.run(), RunError);
}

TEST(RobustRawlogs, AbsurdElementCountIsAnErrorNotGigabytes)
{
	// Found by tests/fuzz/fuzz_rawlog: MRPT resizes a CActionCollection / CSensoryFrame
	// to the stored count before reading any element; 0x6d9c6da1 elements = 29 GB.
	for (const auto& [name, version] : std::vector<std::pair<std::string, char>>{
			 {"mrpt::obs::CActionCollection", 0}, {"mrpt::obs::CSensoryFrame", 2}})
	{
		std::string b;
		b += char(0x80 | name.size());
		b += name;
		b += version;
		b += std::string("\xa1\x6d\x9c\x6d", 4);
		b += std::string(64, '\0');
		const std::string f = tmpFile("absurd_count.rawlog");
		spit(f, b);
		const auto r = readAll(f);
		EXPECT_TRUE(r.threw) << name;
		EXPECT_NE(r.error.find("claims"), std::string::npos) << r.error;
	}
}

namespace
{
/** A sensory-frame rawlog of two steps: a CActionCollection holding `move`, then a
 * frame with one depth image. */
std::string movementRawlog(const mrpt::obs::CActionRobotMovement2D& move)
{
	mrpt::io::CMemoryStream buf;
	auto ar = mrpt::serialization::archiveFrom(buf);
	for (int k = 0; k < 2; k++)
	{
		mrpt::obs::CActionCollection acts;
		acts.insert(move);
		ar << acts;
		mrpt::obs::CSensoryFrame sf;
		sf.insert(testscene::renderDepth(robust::floorAndBox(), robust::kMount, {}, 64, 48));
		ar << sf;
	}
	return std::string(static_cast<const char*>(buf.getRawBufferData()), buf.getTotalBytesCount());
}
}  // namespace

TEST(RobustRawlogs, AMovementWhosePosePdfIsAnotherClassIsAnErrorNotACrash)
{
	// Found by tests/fuzz/fuzz_rawlog (a SIGSEGV in CI): a CActionRobotMovement2D
	// whose estimation method is not odometry reads a pose PDF; MRPT 2.5 turns a
	// stored object of another class into a null pointer and clones it.
	mrpt::obs::CActionRobotMovement2D odo;
	odo.computeFromOdometry(mrpt::poses::CPose2D(0.5, 0, 0), {});
	std::string bytes = movementRawlog(odo);

	// As written: two frames, the robot 0.5 m further at each.
	const std::string f = tmpFile("movement.rawlog");
	spit(f, bytes);
	{
		RawlogFrameReader rd(f);
		Frame fr;
		ASSERT_TRUE(rd.next(fr));
		EXPECT_NEAR(fr.robotPose.x(), 0.5, 1e-9);
		ASSERT_TRUE(rd.next(fr));
		EXPECT_NEAR(fr.robotPose.x(), 1.0, 1e-9);
		EXPECT_FALSE(rd.next(fr));
	}

	// The estimation method (int32 after the class name and the version byte) set to
	// 1, scan matching: what follows, the odometry's CPose2D, is read as the PDF.
	const std::string name = "mrpt::obs::CActionRobotMovement2D";
	const size_t at = bytes.find(name);
	ASSERT_NE(at, std::string::npos);
	ASSERT_EQ(bytes.substr(at + name.size() + 1, 4), std::string(4, '\0'));
	bytes[at + name.size() + 1] = 1;
	expectReadError(
		bytes,
		"at entry 0 (corrupt: a CActionRobotMovement2D holds a 'mrpt::poses::CPose2D' where its pose PDF should be)");

	// The same as the first object of the file, outside a collection.
	expectReadError(bytes.substr(at - 1), "where its pose PDF should be");

	// MRPT also finds a class by its name without the namespace: a collection named
	// "mrpt::/bs::CActionCollection" is read as one (found by the fuzzer, past the
	// first version of this check, which compared names).
	std::string renamed = bytes;
	const size_t ns = renamed.find("mrpt::obs::CActionCollection");
	ASSERT_NE(ns, std::string::npos);
	renamed[ns + 6] = '/';
	expectReadError(renamed, "where its pose PDF should be");
}

TEST(RobustRawlogs, AnAbsurdMotionModelParticleCountIsAnErrorNotGigabytes)
{
	// Found by tests/fuzz/fuzz_rawlog: with odometry and Thrun's motion model, MRPT
	// allocates the stored particle count before anything else is checked.
	mrpt::obs::CActionRobotMovement2D odo;
	mrpt::obs::CActionRobotMovement2D::TMotionModelOptions thrun;
	thrun.modelSelection = mrpt::obs::CActionRobotMovement2D::mmThrun;
	thrun.thrunModel.nParticlesCount = 4321;  // a count easy to find in the bytes
	odo.computeFromOdometry(mrpt::poses::CPose2D(0.5, 0, 0), thrun);
	std::string bytes = movementRawlog(odo);
	const std::string f = tmpFile("particles.rawlog");
	spit(f, bytes);
	EXPECT_FALSE(readAll(f).threw);
	EXPECT_EQ(readAll(f).frames, 2u);

	const std::string count("\xe1\x10\x00\x00", 4);  // 4321, little-endian
	const size_t at = bytes.find(count, bytes.find("mrpt::obs::CActionRobotMovement2D"));
	ASSERT_NE(at, std::string::npos);
	bytes.replace(at, 4, std::string("\x00\x00\x00\x40", 4));  // 2^30 particles
	expectReadError(bytes, "asks for 1073741824 motion-model particles");
}

TEST(RobustRawlogs, AMovementFromScanMatchingMovesTheRobotByItsPdfMean)
{
	// The checked reading of action collections keeps a real PDF: scan matching,
	// a Gaussian of mean (0.3, 0.1, 0.2 rad), gives frames at its mean, then twice it.
	mrpt::obs::CActionRobotMovement2D sm;
	sm.estimationMethod = mrpt::obs::CActionRobotMovement2D::emScan2DMatching;
	sm.poseChange = mrpt::poses::CPosePDFGaussian::Create(mrpt::poses::CPose2D(0.3, 0.1, 0.2));
	const std::string f = tmpFile("scan_matching.rawlog");
	spit(f, movementRawlog(sm));
	RawlogFrameReader rd(f);
	Frame fr;
	ASSERT_TRUE(rd.next(fr));
	EXPECT_NEAR(fr.robotPose.x(), 0.3, 1e-9);
	EXPECT_NEAR(fr.robotPose.y(), 0.1, 1e-9);
	EXPECT_NEAR(fr.robotPose.yaw(), 0.2, 1e-9);
	ASSERT_TRUE(rd.next(fr));
	// (0.3, 0.1, 0.2) composed with itself: x = 0.3 + 0.3 cos 0.2 - 0.1 sin 0.2,
	// y = 0.1 + 0.3 sin 0.2 + 0.1 cos 0.2, yaw 0.4.
	EXPECT_NEAR(fr.robotPose.x(), 0.3 + 0.3 * std::cos(0.2) - 0.1 * std::sin(0.2), 1e-9);
	EXPECT_NEAR(fr.robotPose.y(), 0.1 + 0.3 * std::sin(0.2) + 0.1 * std::cos(0.2), 1e-9);
	EXPECT_NEAR(fr.robotPose.yaw(), 0.4, 1e-9);
	EXPECT_FALSE(rd.next(fr));
}

TEST(RobustRawlogs, AnAbsurdPointCountIsAnErrorNotGigabytes)
{
	// Found by tests/fuzz/fuzz_rawlog: MRPT allocates a 3D scan's five point buffers
	// (16 bytes a point) for the stored count before reading a point. 4321 points
	// written, the count then set to 2^26, twice the limit: 1 GiB allocated before the
	// read failed. Both as an observation and inside a sensory frame.
	auto scan = mrpt::obs::CObservation3DRangeScan::Create();
	scan->hasPoints3D = true;
	scan->resizePoints3DVectors(4321);
	for (size_t i = 0; i < 4321; i++)
	{
		scan->points3D_x[i] = 1.0f + 0.001f * float(i);
		scan->points3D_y[i] = 0;
		scan->points3D_z[i] = -1.0f;
	}
	for (const bool inFrame : {false, true})
	{
		mrpt::io::CMemoryStream buf;
		auto ar = mrpt::serialization::archiveFrom(buf);
		if (inFrame)
		{
			mrpt::obs::CSensoryFrame sf;
			sf.insert(scan);
			ar << sf;
		}
		else
			ar << *scan;
		std::string bytes(static_cast<const char*>(buf.getRawBufferData()), buf.getTotalBytesCount());
		const std::string f = tmpFile("points.rawlog");
		spit(f, bytes);
		const auto r = readAll(f);
		EXPECT_FALSE(r.threw) << r.error;
		EXPECT_EQ(r.frames, 1u);

		const std::string count("\xe1\x10\x00\x00", 4);  // 4321, little-endian
		const size_t at = bytes.find(count, bytes.find("mrpt::obs::CObservation3DRangeScan"));
		ASSERT_NE(at, std::string::npos);
		bytes.replace(at, 4, std::string("\x00\x00\x00\x04", 4));
		expectReadError(bytes, "claims 67108864 points");
	}
}

TEST(RobustRawlogs, AContainerHoldingAnotherKindOfObjectIsAnError)
{
	// Found by tests/fuzz/fuzz_rawlog: an action collection whose element is another
	// action collection, which MRPT read in full (its count allocated as is) only to
	// drop it: a corrupt rawlog. So is a sensory frame holding an action collection.
	for (const bool inFrame : {false, true})
	{
		mrpt::io::CMemoryStream buf;
		auto ar = mrpt::serialization::archiveFrom(buf);
		const std::string inner = "\x9cmrpt::obs::CActionCollection";  // an empty collection
		const std::string outer = inFrame ? "mrpt::obs::CSensoryFrame" : "mrpt::obs::CActionCollection";
		std::string bytes;
		bytes += char(0x80 | outer.size());
		bytes += outer;
		bytes += char(inFrame ? 2 : 0);               // version
		bytes += std::string("\x01\x00\x00\x00", 4);  // one element
		bytes += inner;
		bytes += char(0);               // its version
		bytes += std::string(4, '\0');  // no elements
		bytes += "\x88\x88";            // the end bytes of both
		expectReadError(bytes, "holds a 'mrpt::obs::CActionCollection'");
	}
}

TEST(RobustRawlogs, AbsurdStringLengthIsAnErrorNotGigabytes)
{
	// Found by tests/fuzz/fuzz_rawlog: a corrupt string length (here in a camera
	// name) made MRPT allocate and zero up to 4 GiB before failing. Programs linking
	// ground_mapper refuse strings over 64 MiB.
	mrpt::io::CMemoryStream buf;
	auto ar = mrpt::serialization::archiveFrom(buf);
	ar << uint32_t(0xF0000000u) << uint64_t(0);
	buf.Seek(0);
	std::string s;
	EXPECT_THROW(ar >> s, std::runtime_error);
	// Normal strings still read back.
	mrpt::io::CMemoryStream ok;
	auto ar2 = mrpt::serialization::archiveFrom(ok);
	ar2 << std::string("KINECT");
	ok.Seek(0);
	ar2 >> s;
	EXPECT_EQ(s, "KINECT");
}
