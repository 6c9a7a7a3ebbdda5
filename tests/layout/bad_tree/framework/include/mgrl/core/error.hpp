#pragma once
// The core stage's error header, so that fine.cpp's include resolves.
