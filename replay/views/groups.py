def blueprint(name):
    return None
def log(*a):
    pass
