"""skyscatter.transport"""
