#include "pipeline/alarm.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace leakmon::pipeline {
namespace {

AlarmSettings settings(double on_delay, double off_delay, bool latching) {
  return AlarmSettings{1.0, 0.5, on_delay, off_delay, latching};
}

TEST(Alarm, DeadbandKeepsStateBetweenThresholds) {
  Alarm alarm(settings(0, 0, false));
  EXPECT_TRUE(alarm.update(1.2, 0.0).raised);
  for (double score : {0.9, 0.6, 0.51, 0.99}) {
    EXPECT_FALSE(alarm.update(score, 1.0).any()) << score;
    EXPECT_EQ(alarm.state(), AlarmState::active_unacknowledged);
  }
  EXPECT_TRUE(alarm.update(0.5, 2.0).cleared);
  EXPECT_EQ(alarm.state(), AlarmState::normal);
  EXPECT_FALSE(alarm.update(0.99, 3.0).any()) << "below the raise threshold";
}

TEST(Alarm, OnDelayNeedsTheConditionToHold) {
  Alarm alarm(settings(2.0, 0, false));
  EXPECT_FALSE(alarm.update(1.5, 10.0).any());
  EXPECT_FALSE(alarm.update(1.5, 11.0).any());
  EXPECT_FALSE(alarm.update(0.8, 11.5).any()) << "a dip below raise restarts the delay";
  EXPECT_FALSE(alarm.update(1.5, 12.0).any());
  EXPECT_FALSE(alarm.update(1.5, 13.9).any());
  EXPECT_TRUE(alarm.update(1.5, 14.0).raised);
}

TEST(Alarm, OffDelayNeedsTheReturnToHold) {
  Alarm alarm(settings(0, 3.0, false));
  ASSERT_TRUE(alarm.update(2.0, 0.0).raised);
  EXPECT_FALSE(alarm.update(0.1, 1.0).any());
  EXPECT_FALSE(alarm.update(0.7, 2.0).any()) << "inside the deadband restarts the off-delay";
  EXPECT_FALSE(alarm.update(0.1, 3.0).any());
  EXPECT_FALSE(alarm.update(0.1, 5.9).any());
  EXPECT_TRUE(alarm.update(0.1, 6.0).cleared);
}

TEST(Alarm, NanScoreHoldsEverything) {
  Alarm alarm(settings(1.0, 0, false));
  EXPECT_FALSE(alarm.update(1.5, 0.0).any());
  EXPECT_FALSE(alarm.update(NAN, 0.5).any());
  EXPECT_TRUE(alarm.update(1.5, 1.0).raised) << "a NaN hop neither raises nor restarts";
  EXPECT_FALSE(alarm.update(NAN, 2.0).any());
  EXPECT_TRUE(alarm.active());
}

TEST(Alarm, NonLatchingAcknowledgeThenClear) {
  Alarm alarm(settings(0, 0, false));
  ASSERT_TRUE(alarm.update(2.0, 0.0).raised);
  const auto ack = alarm.acknowledge();
  EXPECT_TRUE(ack.acknowledged);
  EXPECT_FALSE(ack.cleared);
  EXPECT_EQ(alarm.state(), AlarmState::active_acknowledged);
  EXPECT_FALSE(alarm.acknowledge().any()) << "acknowledging twice changes nothing";
  EXPECT_TRUE(alarm.update(0.0, 1.0).cleared);
  EXPECT_EQ(alarm.state(), AlarmState::normal);
}

TEST(Alarm, LatchedAlarmStaysUntilAcknowledged) {
  Alarm alarm(settings(0, 0, true));
  ASSERT_TRUE(alarm.update(2.0, 0.0).raised);
  EXPECT_FALSE(alarm.update(0.0, 1.0).any()) << "latched: returning to normal does not clear";
  EXPECT_EQ(alarm.state(), AlarmState::returned_unacknowledged);
  EXPECT_TRUE(alarm.active());
  EXPECT_FALSE(alarm.update(2.0, 2.0).any()) << "coming back while latched is no new raise";
  EXPECT_EQ(alarm.state(), AlarmState::active_unacknowledged);
  EXPECT_FALSE(alarm.update(0.0, 3.0).any());
  const auto ack = alarm.acknowledge();
  EXPECT_TRUE(ack.acknowledged);
  EXPECT_TRUE(ack.cleared);
  EXPECT_EQ(alarm.state(), AlarmState::normal);
}

TEST(Alarm, LatchedAcknowledgedWhileActiveClearsOnReturn) {
  Alarm alarm(settings(0, 0, true));
  ASSERT_TRUE(alarm.update(2.0, 0.0).raised);
  EXPECT_TRUE(alarm.acknowledge().acknowledged);
  EXPECT_TRUE(alarm.update(0.0, 1.0).cleared);
}

}  // namespace
}  // namespace leakmon::pipeline
