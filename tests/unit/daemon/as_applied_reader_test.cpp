// SPDX-License-Identifier: Apache-2.0
#include "daemon/records/as_applied_reader.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <fstream>

#include "daemon/records/as_applied_log.hpp"

namespace weedspray::daemon {
namespace {

namespace fs = std::filesystem;

class AsAppliedReaderTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ =
        fs::temp_directory_path() /
        ("weedspray-reader-" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) +
         "-" + ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  // n records of 0.01 L each, 0.1 s apart, flushed; returns the file.
  fs::path write_records(int n) {
    AsAppliedLog log(dir_, 1 << 20, 5);
    for (int i = 0; i < n; ++i) {
      AppliedRecord r;
      r.time = std::chrono::milliseconds(100 * i);
      r.volume_l = 0.01;
      r.nozzles = 2;
      EXPECT_TRUE(log.write(r));
    }
    log.flush();
    return log.current_file();
  }

  fs::path dir_;
};

TEST_F(AsAppliedReaderTest, SumsEveryRecordsVolume) {
  write_records(50);
  const AsAppliedSummary s = read_as_applied_dir(dir_);
  EXPECT_EQ(s.files, 1U);
  EXPECT_EQ(s.records, 50U);
  EXPECT_NEAR(s.volume_l, 0.5, 1e-9);
  EXPECT_DOUBLE_EQ(s.first_time_s, 0.0);
  EXPECT_NEAR(s.last_time_s, 4.9, 1e-9);
  EXPECT_EQ(s.torn_tail_lines, 0U);
  EXPECT_EQ(s.damaged_lines, 0U);
}

TEST_F(AsAppliedReaderTest, ATornLastLineIsSkippedAndCounted) {
  const fs::path file = write_records(10);
  // A power cut in the middle of a line: no newline, half the fields.
  std::ofstream(file, std::ios::app) << "1.0000,0.5000,1.0";
  const AsAppliedSummary s = read_as_applied_file(file);
  EXPECT_EQ(s.records, 10U);
  EXPECT_NEAR(s.volume_l, 0.1, 1e-9);
  EXPECT_EQ(s.torn_tail_lines, 1U);
  EXPECT_EQ(s.damaged_lines, 0U);
}

TEST_F(AsAppliedReaderTest, AllFieldsButNoNewlineIsTornToo) {
  const fs::path file = write_records(3);
  std::ofstream(file, std::ios::app) << "0.3000,0,0,0,0,0.0100000,0,0,0,0,0,0";
  const AsAppliedSummary s = read_as_applied_file(file);
  EXPECT_EQ(s.records, 3U);
  EXPECT_EQ(s.torn_tail_lines, 1U);
}

TEST_F(AsAppliedReaderTest, DamageInsideTheFileIsCountedApart) {
  const fs::path file = write_records(2);
  // A whole line after the damage: as many fields as the header (its map columns empty).
  std::string header;
  std::getline(std::ifstream(file), header);
  std::string whole = "0.3000,0,0,0,0,0.0200000";
  for (auto commas = std::count(header.begin(), header.end(), ',') - 5; commas > 0; --commas)
    whole += ",0";
  std::ofstream(file, std::ios::app) << "garbage\n" << whole << "\n";
  const AsAppliedSummary s = read_as_applied_file(file);
  EXPECT_EQ(s.records, 3U);
  EXPECT_NEAR(s.volume_l, 0.04, 1e-9);
  EXPECT_EQ(s.damaged_lines, 1U);
  EXPECT_EQ(s.torn_tail_lines, 0U);
}

// A start reads the records after the totals' mark from the newest files only, and the seq
// runs on from the log's last record.
TEST_F(AsAppliedReaderTest, TheRecordsAfterASeqComeFromTheNewestFiles) {
  {
    AsAppliedLog log(dir_, 4096, 100);  // ~40 records a file
    for (int i = 0; i < 200; ++i) {
      AppliedRecord r;
      r.time = std::chrono::milliseconds(100 * i);
      r.volume_l = 0.01 * (i + 1);  // record seq s holds 0.01 s L
      r.nozzles = 2;
      ASSERT_TRUE(log.write(r));
    }
    log.flush();
  }
  const AsAppliedSummary whole = read_as_applied_dir(dir_);
  ASSERT_GT(whole.files, 3U);
  EXPECT_EQ(whole.first_seq, 1U);
  EXPECT_EQ(whole.last_seq, 200U);
  const AsAppliedSummary after = read_as_applied_after(dir_, 150);
  EXPECT_EQ(after.records, 50U);
  EXPECT_EQ(after.first_seq, 151U);
  EXPECT_EQ(after.last_seq, 200U);
  EXPECT_NEAR(after.volume_l, 0.01 * (151 + 200) * 50 / 2, 1e-9);
  EXPECT_LT(after.files, whole.files) << "the older files are not read";
  EXPECT_EQ(read_as_applied_after(dir_, 0).records, 200U);
  EXPECT_EQ(read_as_applied_after(dir_, 200).records, 0U);
  EXPECT_EQ(last_as_applied_seq(dir_), 200U);
  AsAppliedLog next_run(dir_, 4096, 100);
  next_run.continue_after(last_as_applied_seq(dir_));
  AppliedRecord r;
  r.nozzles = 2;
  ASSERT_TRUE(next_run.write(r));
  next_run.flush();
  EXPECT_EQ(read_as_applied_after(dir_, 200).first_seq, 201U);
  EXPECT_EQ(next_run.progress().seq, 201U);
}

// A crash between creating a file and writing its header leaves it empty: no records, no error.
TEST_F(AsAppliedReaderTest, AnEmptyFileHoldsNoRecords) {
  write_records(3);
  std::ofstream(dir_ / "as-applied-99999999T999999Z-000.csv");
  const AsAppliedSummary s = read_as_applied_dir(dir_);
  EXPECT_EQ(s.files, 2U);
  EXPECT_EQ(s.records, 3U);
  EXPECT_EQ(last_as_applied_seq(dir_), 3U);
}

TEST_F(AsAppliedReaderTest, ANonLogFileIsNamed) {
  fs::create_directories(dir_);
  const fs::path file = dir_ / "as-applied-x.csv";
  std::ofstream(file) << "a,b\n1,2\n";
  try {
    read_as_applied_file(file);
    FAIL() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(file.string()), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace weedspray::daemon
