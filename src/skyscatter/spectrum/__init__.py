"""skyscatter.spectrum"""
