"""skyscatter.render"""
