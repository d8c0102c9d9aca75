#version 450
// GPU impulse generation (being written).
layout(local_size_x = 64) in;
void main() {}
