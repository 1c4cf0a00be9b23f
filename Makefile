# The two set-up commands of the README, and the pieces they share.
#   make demo   install what is missing, build, run the demo
#   make test   install what is missing, build, run every test (gtest + rostest)
#   make build  build only; every tool is then build/bin/<tool>
#   make bench  benchmark figures for docs/benchmarks.md
#   make bench-long  10 minutes of the rendered hall: memory per keyframe, time against map size
#   make screenshots  rviz pictures for docs/ and the README (installs rviz, xvfb, imagemagick)
#   make evaluate  the thesis' studies: output/evaluation/report.md (installs matplotlib)
# Use the ROS side (roslaunch, rosrun, nodelets) after `source build/ws/devel/setup.bash`.
SHELL := /bin/bash
.DEFAULT_GOAL := build

REPO := $(CURDIR)
WS := $(REPO)/build/ws
BIN := $(REPO)/build/bin
JOBS ?= $(shell nproc)
# Debian's python3 (catkin needs its modules) must win over any pyenv shim.
export PATH := /usr/bin:/bin:/usr/sbin:/sbin:$(PATH)
export STEREO_FABMAP_SLAM_DATA ?= $(abspath $(REPO)/../shared/data)

SUDO := $(if $(filter 0,$(shell id -u)),,sudo)

# Debian 12 packages the package builds and tests with (ROS 1 from Debian itself).
DEBIAN_PACKAGES := \
  build-essential cmake catkin python3-catkin-pkg \
  ros-core-dev libroscpp-dev ros-message-generation rosbash \
  libnodeletlib-dev libnodeletlib-tools libnodelet-dev pluginlib-dev \
  libtf2-ros-dev libtf2-eigen-dev libcv-bridge-dev libimage-transport-dev \
  libmessage-filters-dev librosbag-dev python3-rosbag python3-rostest \
  libsensor-msgs-dev libgeometry-msgs-dev libnav-msgs-dev libvisualization-msgs-dev \
  libstd-srvs-dev \
  python3-sensor-msgs python3-geometry-msgs python3-nav-msgs python3-visualization-msgs \
  python3-std-srvs python3-tf2-msgs \
  libceres-dev libopencv-dev libopencv-contrib-dev libeigen3-dev libyaml-cpp-dev libopen3d-dev \
  googletest opencv-doc

# The repository is a single catkin package, built standalone by CMake: build tree in
# build/ws/build, devel space (setup.bash, libraries, messages) in build/ws/devel. No src/ link
# back to the repository, which would make a cycle for rospack and roslaunch to crawl.
CMAKE_ARGS := -DCMAKE_BUILD_TYPE=Release -DPYTHON_EXECUTABLE=/usr/bin/python3 \
  -DCATKIN_DEVEL_PREFIX=$(WS)/devel -DSTEREO_FABMAP_SLAM_TOOL_LINK_DIR=$(BIN)
CMAKE_BUILD := cmake --build $(WS)/build --

.PHONY: deps build test demo bench bench-long clean format vocabulary screenshots evaluate sanitize-build

# $(call install_missing,PACKAGES): installs those of the Debian packages not installed yet.
define install_missing
	@missing=$$(for p in $(1); do \
	    dpkg-query -W -f='$${Status}\n' $$p 2>/dev/null | grep -q '^install ok installed' || echo $$p; \
	  done | tr '\n' ' '); \
	if [ -n "$${missing// }" ]; then \
	  echo "Installing missing Debian packages: $$missing"; \
	  $(SUDO) apt-get update -q && \
	  DEBIAN_FRONTEND=noninteractive $(SUDO) apt-get install -y -q --no-install-recommends $$missing; \
	fi
endef

deps:
	$(call install_missing,$(DEBIAN_PACKAGES))

$(WS)/build/Makefile:
	cmake -S $(REPO) -B $(WS)/build $(CMAKE_ARGS)

# Later builds re-run CMake by themselves when a CMakeLists.txt or package.xml changes.
build: deps $(WS)/build/Makefile
	$(CMAKE_BUILD) -j$(JOBS)
	@$(MAKE) --no-print-directory $(FABMAP_DEFAULT)/detector_model.yaml

# The default FAB-MAP vocabulary (config/fabmap.yaml points at it), trained once from images
# every fresh machine has: opencv-doc's photos and a rendered sequence of the synthetic hall.
# Never from ../shared/data. `make vocabulary` trains it again.
FABMAP_DEFAULT := build/fabmap/default
$(FABMAP_DEFAULT)/detector_model.yaml:
	@echo "Training the default FAB-MAP vocabulary and detector model (first build only, under a minute)"
	rm -rf build/fabmap/synthetic
	$(BIN)/make_synthetic_sequence --output build/fabmap/synthetic --route figure8 --seconds 20 --seed 7 --no-bag > /dev/null
	$(BIN)/train_fabmap --output $(FABMAP_DEFAULT) --every 5 /usr/share/doc/opencv-doc/examples/data build/fabmap/synthetic
	rm -rf build/fabmap/synthetic

vocabulary: deps $(WS)/build/Makefile
	$(CMAKE_BUILD) -j$(JOBS)
	rm -rf $(FABMAP_DEFAULT)
	@$(MAKE) --no-print-directory $(FABMAP_DEFAULT)/detector_model.yaml

# Builds the test programs in parallel, then runs the rostests one at a time (each starts its
# own master) and the unit tests (gtest, no ROS, no timing) JOBS at a time (two: 380 s against
# 493 s one at a time, on two cores); beside them the sanitizer build and its unit tests (ASan,
# LSan, UBSan), two at a time; and closes with one line "tests: N passed, N failed, N skipped"
# over all of them. The rendered sequences the rostests share with the unit tests
# (SharedSyntheticSequence, 1.7 GB) are removed after.
# The sanitizer build compiles and runs its tests at the lowest priority (nice 19) beside the
# other rostests and the unit tests: those rostests play bags in real time and leave most of a
# core idle, which it takes (fresh-clone runs on a slow machine, apt done: 25.3 min with the
# build before the tests, 22.6 min beside them; its tests after everything else left a core
# idle for two minutes; docs/benchmarks.md). The load rostest runs first, alone: beside the
# compiler, even at nice 19, the tracker took 80 ms a pair instead of 9 and the 5x bag lost the
# track. The restart rostest plays its bag at half speed (100 ms a pair) and kept all 200
# odometry messages beside the nice-19 sanitizer build, so it runs with the others.
# A failed sanitizer build is a failed test case with the end of its log.
SANITIZE_LOG := $(REPO)/build/sanitize-build.log
SANITIZE_TESTS_LOG := $(REPO)/build/sanitizer-tests.log
ROSTESTS := $(sort $(basename $(notdir $(wildcard test/ros/*.test))))
ALONE_ROSTESTS := load
rostest_targets = $(foreach t,$(1),run_tests_stereo_fabmap_slam_rostest_test_ros_$(t).test)
# The default vocabulary (a render and a training, about a minute, mostly one core) is made
# beside the test programs' build, which takes the other core.
test: deps $(WS)/build/Makefile
	$(CMAKE_BUILD) -j$(JOBS)
	@$(MAKE) --no-print-directory $(FABMAP_DEFAULT)/detector_model.yaml & vocabulary=$$!; \
	  $(CMAKE_BUILD) -j$(JOBS) tests || exit 1; wait $$vocabulary
	rm -rf $(WS)/build/test_results
	-$(CMAKE_BUILD) -j1 $(call rostest_targets,$(ALONE_ROSTESTS))
	rm -f $(SANITIZE_LOG).status
	@echo "Building and running the sanitizer build at nice 19 beside the tests (logs: $(SANITIZE_LOG), $(SANITIZE_TESTS_LOG))"
	@( nice -n 19 $(MAKE) --no-print-directory sanitize-build > $(SANITIZE_LOG) 2>&1; \
	   echo $$? > $(SANITIZE_LOG).status; \
	   nice -n 19 bash scripts/sanitizer_tests.sh $(SANITIZE)/devel/lib/stereo_fabmap_slam \
	     $(WS)/build/test_results/sanitizers $(SANITIZE_LOG) > $(SANITIZE_TESTS_LOG) 2>&1 ) & \
	  $(CMAKE_BUILD) -j1 $(call rostest_targets,$(filter-out $(ALONE_ROSTESTS),$(ROSTESTS))); \
	  $(CMAKE_BUILD) -j$(JOBS) run_tests_stereo_fabmap_slam_gtest; \
	  echo "Waiting for the sanitizer build and its tests"; wait; true
	@cat $(SANITIZE_TESTS_LOG)
	rm -rf $(WS)/build/test_sequences
	@/usr/bin/python3 scripts/test_summary.py $(WS)/build/test_results \
	  --expected $(WS)/build/expected_test_results.txt

# The sanitizer build: a second build folder, Debug flags with ASan and UBSan, the ROS-free part
# only (STEREO_FABMAP_SLAM_SANITIZE in CMakeLists.txt). Its tools stay out of build/bin.
SANITIZE := $(REPO)/build/sanitize
sanitize-build: deps
	@test -f $(SANITIZE)/build/Makefile || cmake -S $(REPO) -B $(SANITIZE)/build -DCMAKE_BUILD_TYPE=Debug \
	  -DSTEREO_FABMAP_SLAM_SANITIZE=ON -DPYTHON_EXECUTABLE=/usr/bin/python3 \
	  -DCATKIN_DEVEL_PREFIX=$(SANITIZE)/devel
	cmake --build $(SANITIZE)/build -- -j$(JOBS) tests

demo: build
	bash scripts/demo.sh

# Speed and accuracy figures (docs/benchmarks.md records them); never part of `make test`.
bench: build
	bash scripts/bench.sh

bench-long: build
	bash scripts/bench_long.sh

# rviz with the shipped config under Xvfb, on the EuRoC subset and on the rendered loop.
SCREENSHOT_PACKAGES := rviz xvfb imagemagick
SCREENSHOTS := output/screenshots
screenshots: build
	$(call install_missing,$(SCREENSHOT_PACKAGES))
	mkdir -p $(SCREENSHOTS)
	$(BIN)/euroc_to_bag $(STEREO_FABMAP_SLAM_DATA)/euroc/MH01_first10s $(SCREENSHOTS)/MH01_first10s.bag
	rm -rf $(SCREENSHOTS)/loop
	$(BIN)/make_synthetic_sequence --output $(SCREENSHOTS)/loop --route loop --seconds 40 --seed 1 > /dev/null
	for attempt in 1 2 3; do bash scripts/rviz_screenshot.sh \
	  $(SCREENSHOTS)/MH01_first10s.bag docs/rviz_euroc_mh01.png && break; done
	for attempt in 1 2 3; do RVIZ_VIEW="19 2 3 map" RVIZ_WAIT=60 bash scripts/rviz_screenshot.sh \
	  $(SCREENSHOTS)/loop/sequence.bag docs/rviz_synthetic_loop.png \
	  $(SCREENSHOTS)/loop/stereo_calibration.yaml dense:=true && break; done

# The thesis' studies (descriptors, PnP kernels, keyframe presets, relocalization recall) on
# ../shared/data, opencv-doc's graf pair and rendered routes: output/evaluation/report.md with
# its plots (matplotlib draws them; installed here, not needed by the package itself).
evaluate: build
	$(call install_missing,python3-matplotlib)
	bash scripts/evaluate.sh

clean:
	rm -rf build

format:
	clang-format -i $$(git ls-files '*.cpp' '*.h')
