// Compiles the precompiled headers (cmake/AgexPrecompiledHeaders.cmake); no code of its own.
