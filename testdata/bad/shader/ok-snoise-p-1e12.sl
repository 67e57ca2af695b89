shader far() {
  Ci = color(snoise(P * 1e12));
}
