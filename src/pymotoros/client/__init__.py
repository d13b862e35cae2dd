"""pymotoros.client"""
