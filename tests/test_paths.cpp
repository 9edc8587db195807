// Where the suite finds the source tree and the build folder (CLOUD_SOURCE_DIR and
// CLOUD_BINARY_DIR in the test files call these). Only this file is compiled with the clone's
// paths, so every other test file compiles to the same command in any clone and ccache finds it.
const char* cloud_test_source_dir() { return CLOUD_TEST_SOURCE_DIR; }
const char* cloud_test_binary_dir() { return CLOUD_TEST_BINARY_DIR; }
