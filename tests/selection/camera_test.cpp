#include "scenelod/selection/camera.h"

#include <cmath>

#include <gtest/gtest.h>

using namespace scenelod::selection;

TEST(Camera, PixelSizeFollowsLowTan) {
  Camera c;
  c.fov_y_rad = 1.0f;
  c.viewport_height_px = 500;
  EXPECT_FLOAT_EQ(pixelSize(c, 10.0f), 2.0f * 10.0f * std::tan(0.5f) / 500.0f);
  EXPECT_FLOAT_EQ(pixelSize(c, -3.0f), pixelSize(c, c.near_plane));  // clamped to the near plane
  c.projection = Projection::kOrthographic;
  c.ortho_height = 5.0f;
  EXPECT_FLOAT_EQ(pixelSize(c, 1.0f), 0.01f);
  EXPECT_FLOAT_EQ(pixelSize(c, 1000.0f), 0.01f);
}

TEST(Camera, InvalidCamerasAreRefused) {
  Camera c;
  EXPECT_TRUE(cameraValid(c));
  Camera same = c;
  same.target = same.eye;
  EXPECT_FALSE(cameraValid(same));
  Camera parallel = c;
  parallel.up = glm::vec3(0, 0, 1);  // along the view direction
  EXPECT_FALSE(cameraValid(parallel));
  Camera nan = c;
  nan.eye.x = std::nanf("");
  EXPECT_FALSE(cameraValid(nan));
  Camera fov = c;
  fov.fov_y_rad = 0.0f;
  EXPECT_FALSE(cameraValid(fov));
  Camera planes = c;
  planes.far_plane = planes.near_plane;
  EXPECT_FALSE(cameraValid(planes));
}

TEST(Camera, FrustumCullsSpheresOutsideAndBehind) {
  Camera c;
  c.eye = glm::vec3(0.0f);
  c.target = glm::vec3(0, 0, -1);
  c.fov_y_rad = 1.5707964f;  // 90 degrees
  c.viewport_width_px = c.viewport_height_px = 100;
  const Frustum f = computeFrustum(c);
  EXPECT_TRUE(sphereInFrustum(f, {0, 0, -10}, 1.0f));
  EXPECT_FALSE(sphereInFrustum(f, {0, 0, 10}, 1.0f));      // behind the eye
  EXPECT_FALSE(sphereInFrustum(f, {0, 0, 10}, 9.0f));      // large but still entirely behind
  EXPECT_TRUE(sphereInFrustum(f, {0, 0, 0.5f}, 1.0f));     // straddles the eye
  EXPECT_FALSE(sphereInFrustum(f, {20, 0, -10}, 1.0f));    // right of the 45-degree plane
  EXPECT_TRUE(sphereInFrustum(f, {10.5f, 0, -10}, 1.0f));  // touches it
  EXPECT_FALSE(sphereInFrustum(f, {0, -20, -10}, 1.0f));   // below
  c.projection = Projection::kOrthographic;
  c.ortho_height = 4.0f;
  const Frustum o = computeFrustum(c);
  EXPECT_TRUE(sphereInFrustum(o, {1.5f, 0, -100}, 0.1f));
  EXPECT_FALSE(sphereInFrustum(o, {3.0f, 0, -100}, 0.5f));
  EXPECT_FALSE(sphereInFrustum(o, {0, 0, 5}, 1.0f));
}
