// The donor of the test executables' precompiled header (tests/CMakeLists.txt,
// RIG_TEST_PCH): its compile makes the header; it has no code of its own.
