"""pymotoros.runtime"""
