#include "runtime/tracing.h"

#include <gtest/gtest.h>

namespace meshflow {
namespace {

TEST(Tracing, SummarizesStagesInFirstSeenOrder) {
  std::vector<StageRecord> records = {
      {"b", 0.0, 0.2, 0, 10}, {"a", 0.0, 0.1, 0, 5}, {"b", 1.0, 1.4, 1, 10}};
  const auto s = summarize_stages(records);
  ASSERT_EQ(s.size(), 2u);
  EXPECT_EQ(s[0].stage, "b");
  EXPECT_EQ(s[0].calls, 2u);
  EXPECT_NEAR(s[0].total_s, 0.6, 1e-12);
  EXPECT_NEAR(s[0].max_s, 0.4, 1e-12);
  EXPECT_EQ(s[0].items, 20u);
  EXPECT_NE(format_stage_table(s, 1.0).find("b"), std::string::npos);
  const std::string csv = format_stage_csv(s, 2.0);
  EXPECT_EQ(csv.substr(0, csv.find('\n')),
            "stage,calls,total_ms,mean_ms,p50_ms,p95_ms,max_ms,share,items,items_per_s,wall_ms");
  EXPECT_NE(csv.find("\nb,2,600.0000,300.0000,400.0000,400.0000,400.0000,0.85714,20,"),
            std::string::npos)
      << csv;
}

TEST(Tracing, ChromeTraceHasOneCompleteEventPerRecord) {
  const std::vector<StageRecord> records = {{"read", 10.0, 10.5, 0, 100, 0},
                                            {"normals", 10.5, 11.0, 1, 100, 0},
                                            {"read", 10.2, 10.4, 1, 50, 1}};
  const std::string json = chrome_trace_json(records);
  EXPECT_EQ(json.rfind("{\"displayTimeUnit\":\"ms\",\"traceEvents\":[", 0), 0u);
  std::size_t events = 0;
  for (std::size_t at = json.find("\"ph\":\"X\""); at != std::string::npos;
       at = json.find("\"ph\":\"X\"", at + 1))
    ++events;
  EXPECT_EQ(events, 3u);
  EXPECT_NE(json.find("\"name\":\"read\",\"cat\":\"stage\",\"ph\":\"X\",\"ts\":0.000,\"dur\":"
                      "500000.000,\"pid\":1,\"tid\":0,\"args\":{\"frame\":0,\"items\":100}"),
            std::string::npos)
      << json;
  EXPECT_NE(
      json.find("\"ts\":200000.000,\"dur\":200000.000,\"pid\":1,\"tid\":1,\"args\":{\"frame\":1"),
      std::string::npos)
      << json;
  EXPECT_EQ(json.substr(json.size() - 4), "\n]}\n");
}

}  // namespace
}  // namespace meshflow
