// Determinism: the same scene and seed give a byte-identical rawlog, and the same
// rawlog and .ini give byte-identical mapper outputs, file by file. Only timing.csv
// differs between runs (it holds measured milliseconds); its frame/map/stage
// columns must still match.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

namespace fs = std::filesystem;

#if defined(GAM_MAPPER_EXE) && defined(GAM_SIMULATE_EXE)
namespace
{
const std::string kTmp = std::string(GAM_TEST_TMP_DIR) + "/determinism_p" + std::to_string(getpid());

std::string slurp(const std::string& f)
{
	std::ifstream i(f, std::ios::binary);
	std::ostringstream s;
	s << i.rdbuf();
	return s.str();
}

int sh(const std::string& cmd) { return std::system(cmd.c_str()); }

std::set<std::string> filesIn(const std::string& d)
{
	std::set<std::string> s;
	for (const auto& e : fs::directory_iterator(d)) s.insert(e.path().filename().string());
	return s;
}

/** timing.csv without its ms column. */
std::string timingKeys(const std::string& f)
{
	std::istringstream in(slurp(f));
	std::string line, out;
	while (std::getline(in, line)) out += line.substr(0, line.rfind(',')) + "\n";
	return out;
}
}  // namespace

TEST(Determinism, SameRawlogIniAndSeedGiveByteIdenticalOutputs)
{
	fs::remove_all(kTmp);
	fs::create_directories(kTmp);
	const std::string scene = std::string(GAM_SOURCE_DIR) + "/config/scenes/demo.scene";
	// The simulator: same seed, same bytes.
	for (const char* run : {"a", "b"})
		ASSERT_EQ(
			sh(std::string("'") + GAM_SIMULATE_EXE + "' --scene '" + scene + "' --out '" + kTmp + "/sim_" + run +
			   "/demo' --seed 7 --frames 6 >/dev/null 2>&1"),
			0);
	ASSERT_EQ(slurp(kTmp + "/sim_a/demo.rawlog"), slurp(kTmp + "/sim_b/demo.rawlog")) << "gam-simulate, same seed";
	// The mapper, twice on the same rawlog with the default .ini (every map kind:
	// RRT-GPD with its seeded RNG, the comparison maps, the elevation map).
	const std::string rawlog = kTmp + "/sim_a/demo.rawlog";
	for (const char* run : {"out1", "out2"})
		ASSERT_EQ(
			sh(std::string("'") + GAM_MAPPER_EXE + "' --rawlog '" + rawlog + "' --out '" + kTmp + "/" + run +
			   "' --quiet >/dev/null 2>&1"),
			0);
	const auto f1 = filesIn(kTmp + "/out1"), f2 = filesIn(kTmp + "/out2");
	ASSERT_EQ(f1, f2);
	ASSERT_GE(f1.size(), 15u);
	for (const auto& f : f1)
	{
		const std::string a = slurp(kTmp + "/out1/" + f), b = slurp(kTmp + "/out2/" + f);
		if (f == "timing.csv")
		{
			EXPECT_EQ(timingKeys(kTmp + "/out1/" + f), timingKeys(kTmp + "/out2/" + f));
			continue;
		}
		EXPECT_FALSE(a.empty()) << f;
		EXPECT_TRUE(a == b) << f << " differs between two runs";
	}
	// A different seed gives a different rawlog (the seed is really used).
	ASSERT_EQ(
		sh(std::string("'") + GAM_SIMULATE_EXE + "' --scene '" + scene + "' --out '" + kTmp +
		   "/sim_c/demo' --seed 8 --frames 6 >/dev/null 2>&1"),
		0);
	EXPECT_NE(slurp(kTmp + "/sim_a/demo.rawlog"), slurp(kTmp + "/sim_c/demo.rawlog"));
	fs::remove_all(kTmp);
}
#endif
