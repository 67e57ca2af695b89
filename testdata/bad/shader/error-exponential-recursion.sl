float f(float x) {
  float r = 1;
  if (x > 0) { r = f(x - 1) + f(x - 1); }
  return r;
}
shader s() {
  Ci = f(40);
}
